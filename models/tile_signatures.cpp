#include "models/tile_signatures.hpp"

#include <utility>

namespace tbdr {

void TileSignatures::begin_frame() {
  for (auto& [key, t] : tables_) {
    t.previous = std::move(t.current);
    t.has_previous = std::move(t.has_current);
    t.current.assign(t.previous.size(), 0);
    t.has_current.assign(t.previous.size(), 0);
  }
}

TileSignatures::Table* TileSignatures::prepare(const std::string& key, std::size_t tiles) {
  Table& t = tables_[key];
  if (t.current.size() != tiles) {  // a new table, or the frame's size changed: nothing to compare
    t.previous.assign(tiles, 0);
    t.has_previous.assign(tiles, 0);
    t.current.assign(tiles, 0);
    t.has_current.assign(tiles, 0);
  }
  return &t;
}

}  // namespace tbdr
