#include "kernel/output_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "kernel/errors.hpp"

namespace tbdr {

namespace fs = std::filesystem;

std::string write_failure(const std::string& what, int err) {
  return "cannot write " + what + ": " + (err != 0 ? std::string(std::strerror(err)) : std::string("a write failed")) +
         "; nothing written";
}

PendingOutput::PendingOutput(const std::string& path) : path_(path), target_(path), temp_(path) {
  std::error_code ec;
  const fs::file_status link = fs::symlink_status(path, ec);
  if (fs::is_symlink(link)) {
    const fs::path resolved = fs::canonical(path, ec);
    if (!ec) target_ = resolved.string();
  }
  const fs::file_status st = fs::status(target_, ec);
  if (fs::exists(st) && !fs::is_regular_file(st)) return;  // a device or a pipe: written in place
  const fs::path p(target_);
  temp_ = (p.parent_path() / ("." + p.filename().string() + ".tmp-" + std::to_string(getpid()))).string();
}

PendingOutput::~PendingOutput() {
  if (!committed_ && temp_ != target_) std::remove(temp_.c_str());
}

void PendingOutput::commit() {
  if (temp_ == target_) {
    committed_ = true;
    return;
  }
  if (std::rename(temp_.c_str(), target_.c_str()) != 0) {
    const int err = errno;
    std::remove(temp_.c_str());
    committed_ = true;
    throw InputError(path_, "cannot move the written file into place: " + std::string(std::strerror(err)));
  }
  committed_ = true;
}

void write_output_file(const std::string& path, const std::string& what,
                       const std::function<void(std::ostream&)>& write) {
  PendingOutput pending(path);
  errno = 0;
  std::ofstream out(pending.temp_path(), std::ios::binary | std::ios::trunc);
  if (!out) throw InputError(path, write_failure(what, errno));
  write(out);
  out.flush();
  int err = errno;
  if (out) {
    out.close();
    err = errno;
  }
  if (!out) throw InputError(path, write_failure(what, err));
  pending.commit();
}

void write_output_file(const std::string& path, const std::string& what, std::string_view bytes) {
  write_output_file(path, what, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

}  // namespace tbdr
