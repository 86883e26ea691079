// The unit of a results.h5 dataset (core/io/dataset_units.hpp) is written where the dataset is
// and read back as written, by the engine (a signal trace taken from another scene's
// results.h5 keeps its units) and as h5py and H5MD readers read it (UTF-8 text); a dataset
// without a unit reads as "", and a unit cannot be left empty.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/signal/trace_io.hpp"

using namespace granular;
namespace fs = std::filesystem;

namespace {
std::string fresh_file(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("granular_test_units_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return (dir / "results.h5").string();
}
}  // namespace

TEST(DatasetUnits, UnitWrittenWithADatasetReadsBackAsWritten) {
  const std::string path = fresh_file("roundtrip");
  {
    H5Writer out(path);
    write_quantity(out, "/trace/time", std::vector<double>{0, 1, 2, 3, 4, 5, 6, 7}, "us");
    write_quantity(out, "/trace/amplitude", std::vector<double>{0, 1, 0, -1, 0, 1, 0, -1},
                   "mm us-1");
    write_quantity(out, "/trace/spectrum/energy", std::vector<double>{1, 2}, "MPa+2 us+2");
    write_quantity(out, "/table/id", std::vector<int>{3, 4}, "1");
    out.write("/table/unlabelled", std::vector<double>{1});
    out.attribute("/table/unlabelled", "note", std::string("fixed-length text"));
    out.commit();
  }
  EXPECT_EQ(read_dataset_unit(path, "/trace/time"), "us");
  EXPECT_EQ(read_dataset_unit(path, "/trace/amplitude"), "mm us-1");
  EXPECT_EQ(read_dataset_unit(path, "/trace/spectrum/energy"), "MPa+2 us+2");
  EXPECT_EQ(read_dataset_unit(path, "/table/id"), "1");
  // No unit, no such dataset, no such file: "" (the caller decides what to assume).
  EXPECT_EQ(read_dataset_unit(path, "/table/unlabelled"), "");
  EXPECT_EQ(read_dataset_unit(path, "/table/absent"), "");
  EXPECT_EQ(read_dataset_unit(path + ".missing", "/trace/time"), "");
  // The trace itself reads back as written beside its units.
  const Trace tr = read_trace_h5(path, "/trace/time", "/trace/amplitude");
  EXPECT_EQ(tr.a, (std::vector<double>{0, 1, 0, -1, 0, 1, 0, -1}));
  fs::remove_all(fs::path(path).parent_path());
}

TEST(DatasetUnits, AnEmptyUnitIsRefusedNamingTheDataset) {
  const std::string path = fresh_file("empty");
  H5Writer out(path);
  try {
    write_quantity(out, "/table/M", std::vector<double>{1}, "");
    FAIL() << "no error";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("/table/M"), std::string::npos) << e.what();
  }
  fs::remove_all(fs::path(path).parent_path());
}
