// The allocator settings `main` sets (sim/app/main.cpp): the heap's thresholds in process, and
// transparent huge pages (re-executing the program with them) unless the host takes freed memory
// back (free page reporting), or as TBDRSIM_HUGE_PAGES=1 / 0 says; a user's own GLIBC_TUNABLES
// kept as given. Checked through what a run books
// (frame/host allocator_huge_pages, host_free_page_reporting) when the binary is started with a
// chosen environment.
#include <gtest/gtest.h>
#include <fcntl.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "atrium_trace_setup.hpp"
#include "db_query.hpp"
#include "scene/scene_library.hpp"
#include "scratch_dir.hpp"
#include "app/host_speed.hpp"
#include "techniques/technique.hpp"
#include "trace/trace.hpp"

namespace tbdr {
namespace {

namespace fs = std::filesystem;
testing_scratch::ScratchCleanup scratch_cleanup{"allocator"};

/// Runs `tbdrsim run --trace T --db D` with exactly the environment `env` (PATH aside); returns
/// the run's allocator_huge_pages figure (NaN and a failure when it did not run).
double huge_pages_flag(const std::string& trace, const fs::path& db, std::vector<std::string> env) {
  std::vector<std::string> args = {TBDRSIM_BINARY, "run", "--trace", trace, "--db", db.string(), "--threads", "1"};
  env.push_back("PATH=/usr/bin:/bin");
  std::vector<char*> argv, envp;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  for (auto& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);
  const std::string log = db.string() + ".log";  // (made before the fork: the child only execs)
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    execve(argv[0], argv.data(), envp.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << db;
  return testing_support::query_number(db.string(), "SELECT value FROM stats WHERE scope = 'frame/host' AND name = 'allocator_huge_pages'");
}

TEST(Allocator, HugePagesUnlessTheHostTakesFreedMemoryBackOrTheVariableSaysAndAUsersTunablesKept) {
#if defined(__SANITIZE_ADDRESS__) || !defined(__GLIBC__)
  GTEST_SKIP() << "the sanitizers' allocator (or a libc other than glibc): no re-execution";
#else
  const fs::path dir = testing_scratch::scratch_dir("allocator", "runs");
  const Scene scene = load_scene("atrium:1");
  const std::string trace = (dir / "pf.trace").string();
  write_trace_file(generate_trace("plain_forward", testing_support::atrium_entrance_setup(scene, 4, 64, 32)), trace);
  // Unset: huge pages unless the host takes freed memory back, as the run books it.
  const double by_host = huge_pages_flag(trace, dir / "default.db", {});
  const double reporting = testing_support::query_number(
      (dir / "default.db").string(), "SELECT value FROM stats WHERE scope = 'frame/host' AND name = 'host_free_page_reporting'");
  EXPECT_EQ(reporting, host_reports_free_pages() ? 1.0 : 0.0);
  EXPECT_EQ(by_host, reporting == 1.0 ? 0.0 : 1.0);
  EXPECT_EQ(huge_pages_flag(trace, dir / "off.db", {"TBDRSIM_HUGE_PAGES=0"}), 0.0);
  EXPECT_EQ(huge_pages_flag(trace, dir / "on.db", {"TBDRSIM_HUGE_PAGES=1"}), 1.0);
  // A user's own tunables are not touched (no huge pages added to them).
  EXPECT_EQ(huge_pages_flag(trace, dir / "user.db", {"GLIBC_TUNABLES=glibc.malloc.trim_threshold=1048576"}), 0.0);
#endif
}

// The heap's thresholds set in the running process (what `main` does unless it re-executes for
// huge pages): a 20 MiB block, over glibc's default mmap threshold of 128 KiB, comes from the
// heap; a 40 MiB block, over the 32 MiB set, is still mapped on its own (mallinfo2's hblks counts
// the mapped blocks).
TEST(Allocator, HeapThresholdsSetInProcessKeepBlocksUpTo32MiBInTheHeap) {
#if defined(__SANITIZE_ADDRESS__) || !defined(__GLIBC__)
  GTEST_SKIP() << "the sanitizers' allocator (or a libc other than glibc)";
#else
  ASSERT_TRUE(set_heap_thresholds());
  static void* volatile sink = nullptr;  // (the blocks are used: the compiler keeps the calls)
  const std::size_t mapped_before = mallinfo2().hblks;
  sink = std::malloc(std::size_t{20} << 20);
  const std::size_t mapped_with_20 = mallinfo2().hblks;
  std::free(sink);
  sink = std::malloc(std::size_t{40} << 20);
  const std::size_t mapped_with_40 = mallinfo2().hblks;
  std::free(sink);
  EXPECT_EQ(mapped_with_20, mapped_before);
  EXPECT_EQ(mapped_with_40, mapped_before + 1);
#endif
}

// Free page reporting is read from the balloon devices' feature bits (bit 5,
// VIRTIO_BALLOON_F_REPORTING): set on the Firecracker VM measured 2026-12-06
// ("0110010100..."), clear where the device lacks it, and no device (bare metal) or an
// unreadable or short feature string means no reporting.
TEST(Allocator, FreePageReportingIsTheBalloonsFeatureBitFive) {
  const fs::path dir = testing_scratch::scratch_dir("allocator", "balloon");
  auto device = [&](const std::string& name, const std::string& bits) {
    fs::create_directories(dir / name);
    std::ofstream(dir / name / "features") << bits << "\n";
  };
  EXPECT_FALSE(host_reports_free_pages((dir / "none").string()));  // no such folder
  fs::create_directories(dir / "empty");
  EXPECT_FALSE(host_reports_free_pages((dir / "empty").string()));
  device("clear/virtio0", "0110000100000000000000000000000010000000");
  EXPECT_FALSE(host_reports_free_pages((dir / "clear").string()));
  device("short/virtio0", "01100");
  EXPECT_FALSE(host_reports_free_pages((dir / "short").string()));
  device("set/virtio0", "0110010100000000000000000000000010000000");
  EXPECT_TRUE(host_reports_free_pages((dir / "set").string()));
  device("second/virtio0", "0000000");
  device("second/virtio3", "0000010");
  EXPECT_TRUE(host_reports_free_pages((dir / "second").string()));  // any device with the bit
}

}  // namespace
}  // namespace tbdr
