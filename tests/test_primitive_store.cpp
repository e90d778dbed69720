// PrimitiveStore (models/render_state.hpp): a render's primitive records, indexed like a vector,
// in chunks that never move: records keep their addresses and values as the store grows past
// chunk boundaries, and a cleared store reuses its chunks.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "models/render_state.hpp"

namespace tbdr {
namespace {

Primitive numbered(std::uint32_t i) {
  Primitive p;
  p.id = i;
  p.draw = i * 3u;
  p.proxy_light = static_cast<std::int32_t>(i % 7u);
  return p;
}

TEST(PrimitiveStore, RecordsKeepTheirAddressesAndValuesAcrossChunks) {
  PrimitiveStore store;
  // Three chunks and a bit: 3 x 16384 + 5 records.
  const std::size_t n = 3 * PrimitiveStore::kChunkRecords + 5;
  std::vector<const Primitive*> addresses;
  for (std::uint32_t i = 0; i < n; ++i) addresses.push_back(&store.emplace_back(numbered(i)));
  ASSERT_EQ(store.size(), n);
  for (std::uint32_t i = 0; i < n; ++i) {
    EXPECT_EQ(&store[i], addresses[i]) << i;  // never moved by the growth after it
    EXPECT_EQ(store[i].id, i);
    EXPECT_EQ(store[i].draw, i * 3u);
  }
  // Chunk boundaries: the last record of a chunk and the first of the next are neighbours in
  // index only.
  EXPECT_EQ(store[PrimitiveStore::kChunkRecords - 1].id, PrimitiveStore::kChunkRecords - 1);
  EXPECT_EQ(store[PrimitiveStore::kChunkRecords].id, PrimitiveStore::kChunkRecords);
  EXPECT_EQ(store.back().id, n - 1);
  store.pop_back();
  EXPECT_EQ(store.size(), n - 1);
  EXPECT_EQ(store.back().id, n - 2);
}

TEST(PrimitiveStore, ClearedStoreReusesItsChunks) {
  PrimitiveStore store;
  for (std::uint32_t i = 0; i < 100; ++i) store.push_back(numbered(i));
  const Primitive* first = &store[0];
  store.clear();
  EXPECT_TRUE(store.empty());
  // The next render's first record goes where the last render's did: no new allocation.
  EXPECT_EQ(&store.emplace_back(numbered(42)), first);
  EXPECT_EQ(store[0].id, 42u);
  // Moved between passes (FrameSimulator keeps it), the chunks go with it.
  PrimitiveStore kept = std::move(store);
  EXPECT_EQ(&kept[0], first);
  EXPECT_EQ(kept.size(), 1u);
  EXPECT_TRUE(store.empty());  // NOLINT(bugprone-use-after-move): the source is left empty
}

}  // namespace
}  // namespace tbdr
