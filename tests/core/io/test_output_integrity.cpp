// Output files are whole or absent: a write that runs out of space (a file-size limit stands
// in for a full disk, which a test cannot make) fails with a clear error and leaves the
// previous complete file under its name and no partial file behind; the plotting hook
// hands paths to the interpreter as they are, so a hostile directory name runs nothing.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/output.hpp"
#include "core/run/error.hpp"
#include "scenarios/common/charts.hpp"

using namespace granular;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  const auto dir =
      fs::temp_directory_path() / ("granular_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Limits the size of any file this process writes, for the scope's lifetime; writes past
// the limit fail with EFBIG, as on a full disk (SIGXFSZ, which would kill us, is ignored).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &saved_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit lim = saved_;
    lim.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &lim);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit saved_{};
  void (*old_handler_)(int) = nullptr;
};

std::string read_text(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

}  // namespace

TEST(OutputIntegrity, HdfFileThatCannotBeWrittenWholeLeavesThePreviousOneInPlace) {
  const auto dir = fresh_dir("h5_full");
  const std::string path = (dir / "results.h5").string();
  {
    H5Writer w(path);
    w.write("/a", std::vector<double>{1, 2, 3});
    w.commit();
  }
  bool failed = false;
  {
    std::optional<H5Writer> w;
    w.emplace(path);
    {
      FileSizeLimit limit(64 * 1024);
      try {
        w->write("/a", std::vector<double>(1 << 17, 7.0));  // 1 MiB: past the limit
        w->commit();
      } catch (const std::exception& e) {
        failed = true;
        EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos) << e.what();
      }
    }
    // Space is back when the writer is dropped (as after a transient full disk): it must
    // close the file and remove the partial one, not commit it.
  }
  EXPECT_TRUE(failed) << "a write past the space left must fail";
  EXPECT_EQ(H5Reader(path).reals("/a"), (std::vector<double>{1, 2, 3}));
  EXPECT_FALSE(fs::exists(partial_name(path)));
  fs::remove_all(dir);
}

// When the space never comes back, the run reports the failure naming the file, and the
// process must still end normally: a file HDF5 itself failed to write and close stayed open
// inside the library, whose clean-up at exit then crashed (SIGSEGV). A child process, so
// that the library's exit really runs, with the file-size limit kept to the end.
TEST(OutputIntegrity, DiskThatStaysFullGivesOneClearErrorAndNoLibraryDumpAtExit) {
  const auto dir = fresh_dir("h5_stays_full");
  const std::string path = (dir / "results.h5").string();
  const fs::path err = dir / "stderr.txt";
  std::fflush(nullptr);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (!std::freopen(err.c_str(), "w", stderr)) std::_Exit(3);
    FileSizeLimit limit(64 * 1024);  // kept until exit: the disk stays full
    try {
      H5Writer w(path);
      w.write("/a", std::vector<double>(1 << 17, 7.0));
      w.commit();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "run error: %s\n", e.what());
      std::exit(0);  // the normal exit path, with the library's clean-up
    }
    std::exit(4);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "the child died of signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0) << "4: the write did not fail; 3: no stderr file";
  const std::string text = read_text(err);
  EXPECT_NE(text.find("run error: "), std::string::npos) << text;
  EXPECT_NE(text.find(dir.string()), std::string::npos) << text;
  EXPECT_EQ(text.find("HDF5-DIAG"), std::string::npos) << text;  // the library's dump
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(partial_name(path)));
  fs::remove_all(dir);
}

TEST(OutputIntegrity, TextFileThatCannotBeWrittenWholeLeavesThePreviousOneInPlace) {
  const auto dir = fresh_dir("text_full");
  const std::string path = (dir / "summary.json").string();
  write_text_file(path, "{\"complete\": true}\n");
  bool failed = false;
  {
    FileSizeLimit limit(4096);
    try {
      write_text_file(path, std::string(1 << 16, 'x'));
    } catch (const std::exception& e) {
      failed = true;
      EXPECT_NE(std::string(e.what()).find("summary.json"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(failed);
  EXPECT_EQ(read_text(path), "{\"complete\": true}\n");
  EXPECT_FALSE(fs::exists(partial_name(path)));
  fs::remove_all(dir);
}

TEST(OutputIntegrity, OutputIntoAMissingDirectoryIsAnErrorNotACrash) {
  const auto dir = fresh_dir("no_dir");
  const std::string path = (dir / "absent" / "results.h5").string();
  EXPECT_THROW(
      {
        H5Writer w(path);
        w.commit();
      },
      std::exception);
  EXPECT_THROW(write_text_file(path + ".json", "{}"), std::exception);
  EXPECT_FALSE(fs::exists(path));
  fs::remove_all(dir);
}

TEST(OutputIntegrity, PlotHookPassesHostilePathsVerbatimAndRunsNoShell) {
  if (!fs::exists("/usr/bin/python3")) GTEST_SKIP() << "no /usr/bin/python3";
  const auto dir = fresh_dir("plot_hook");
  // A stand-in chart script that records the arguments it was given.
  const auto scripts = dir / "plots";
  fs::create_directories(scripts);
  std::ofstream(scripts / "record_args.py")
      << "import sys\nopen(sys.argv[2] + '/args.txt', 'w').write('\\n'.join(sys.argv[1:]))\n";
  const std::string marker = (dir / "pwned").string();
  const fs::path hostile = dir / ("out' ; touch '" + marker + "' ; echo '$(id)`id`\"");
  fs::create_directories(hostile);
  const std::string h5 = (hostile / "results.h5").string();
  ::setenv("GRANULAR_PLOTS_DIR", scripts.c_str(), 1);
  const bool ok = run_plot_script("record_args.py", h5, hostile.string());
  ::unsetenv("GRANULAR_PLOTS_DIR");
  EXPECT_TRUE(ok);
  EXPECT_FALSE(fs::exists(marker)) << "a shell ran the path";
  EXPECT_EQ(read_text(hostile / "args.txt"), h5 + "\n" + hostile.string());
  fs::remove_all(dir);
}

// A dataset whose header declares far more values than the file holds (a garbled extent) is
// refused naming the file and the dataset, before anything is allocated; reading it used to
// allocate the declared size (3.8 GB, then bad_alloc, the file not named).
TEST(OutputIntegrity, DatasetDeclaringMoreThanItsFileHoldsIsRefusedBeforeAllocating) {
  const std::string path =
      ::testing::TempDir() + "granular_garbled_extent_" + std::to_string(::getpid()) + ".h5";
  {
    // Contiguous storage allocated late: the extent is recorded, no data is written.
    const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hsize_t dims[1] = {hsize_t(1) << 32};  // 4 Gi doubles = 32 GiB
    const hid_t space = H5Screate_simple(1, dims, nullptr);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_alloc_time(dcpl, H5D_ALLOC_TIME_LATE);
    const hid_t set =
        H5Dcreate2(file, "huge", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    ASSERT_GE(set, 0);
    H5Dclose(set), H5Pclose(dcpl), H5Sclose(space), H5Fclose(file);
  }
  ASSERT_LT(std::filesystem::file_size(path), 1u << 20);
  const H5Reader r(path);
  try {
    (void)r.reals("huge");
    FAIL() << "a dataset larger than its file was read";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("huge"), std::string::npos) << what;
  }
  std::remove(path.c_str());
}

// Every HDF5 file the engine writes carries a checksum of its bytes: one damaged byte,
// tried at every position of a small file, and the file cut short, are each refused with an
// InputError that names the file. The one exception is the tag that marks a file as
// checksummed: damaged, the file reads as an untagged one, so with the same numbers. Before
// the checksum, six garbled bytes in a checkpoint resumed a run with other results, exit 0.
TEST(OutputIntegrity, EveryDamagedByteOfAWrittenFileIsRefusedOrReadsTheSameNumbers) {
  const std::string path =
      ::testing::TempDir() + "granular_checksummed_" + std::to_string(::getpid()) + ".h5";
  std::vector<double> x(300);
  for (size_t i = 0; i < x.size(); ++i) x[i] = 0.37 * static_cast<double>(i) - 11.0;
  std::vector<int> ids(40);
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<int>(7 * i + 1);
  {
    H5Writer w(path);
    w.write("state/x", x, {100, 3});
    w.write("state/ids", ids);
    w.write("state/empty", std::vector<double>{});
    w.attribute("/", "step", 42.0);
    w.commit();
  }
  {
    const H5Reader r(path);
    ASSERT_EQ(r.reals("state/x"), x);
    ASSERT_EQ(r.ints("state/ids"), ids);
  }
  std::string image;
  {
    std::ifstream in(path, std::ios::binary);
    image.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_GT(image.size(), 2000u);
  int refused = 0, same = 0;
  for (size_t at = 0; at < image.size(); ++at) {
    std::string damaged = image;
    damaged[at] = static_cast<char>(damaged[at] ^ 0x5a);
    {
      std::ofstream out(path, std::ios::binary | std::ios::trunc);
      out << damaged;
    }
    try {
      const H5Reader r(path);
      const bool equal = r.reals("state/x") == x && r.ints("state/ids") == ids &&
                         r.reals("state/empty").empty() && r.attribute("/", "step") == 42.0;
      const size_t tag = sizeof "granular checksummed HDF5 file\nfnv1a64 " - 1;
      ASSERT_TRUE(equal && at < tag)
          << "byte " << at << " of " << image.size() << " damaged, read"
          << " without an error" << (equal ? " (the same numbers)" : " (other numbers)");
      ++same;
    } catch (const InputError& e) {
      ASSERT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      ++refused;
    }
  }
  EXPECT_EQ(refused + same, static_cast<int>(image.size()));
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << image.substr(0, image.size() - 1);
  }
  EXPECT_THROW(H5Reader{path}, InputError) << "a file cut short by one byte was opened";
  std::remove(path.c_str());
}

// A file larger than the checksum's read buffer (1 MiB) is verified piece by piece and
// reads back whole.
TEST(OutputIntegrity, FileLargerThanTheChecksumBufferReadsBackWhole) {
  const std::string path =
      ::testing::TempDir() + "granular_chunks_" + std::to_string(::getpid()) + ".h5";
  std::vector<double> v((size_t(1) << 20) + 17);
  for (size_t i = 0; i < v.size(); ++i) v[i] = std::sqrt(static_cast<double>(i));
  {
    H5Writer w(path);
    w.write("rows", v, {v.size() / 3, 3});
    w.commit();
  }
  EXPECT_EQ(H5Reader(path).reals("rows"), v);
  std::remove(path.c_str());
}
