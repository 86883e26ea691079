// Output files that are never half-written: every file goes to a temporary name in the
// same directory and is renamed into place only once it is complete. HDF5 (C API behind
// RAII), a small JSON builder for summary.json, XDMF sidecars and the plotting hook.
#pragma once
#include <hdf5.h>

#include <map>
#include <memory>
#include <string>
#include <variant>
#include <vector>

namespace granular {

// ---- JSON --------------------------------------------------------------------------
class Json {
 public:
  using Object = std::vector<std::pair<std::string, Json>>;  // keeps insertion order
  using Array = std::vector<Json>;

  Json() : v_(nullptr) {}
  Json(double d) : v_(d) {}
  Json(int i) : v_(static_cast<double>(i)) {}
  Json(long i) : v_(static_cast<double>(i)) {}
  Json(bool b) : v_(b) {}
  Json(const char* s) : v_(std::string(s)) {}
  Json(std::string s) : v_(std::move(s)) {}
  Json(const std::vector<double>& a);
  static Json object() {
    Json j;
    j.v_ = Object{};
    return j;
  }
  static Json array() {
    Json j;
    j.v_ = Array{};
    return j;
  }
  // A value that is undefined by construction when it is not finite (a fit with too few
  // points, a ratio over an empty set): null then. Never for a computed physical result,
  // whose NaN must stop the run (write_summary).
  static Json or_null(double v) { return v - v == 0 ? Json(v) : Json(); }
  // Raw JSON text (already valid), e.g. a value copied from a scene file.
  static Json raw(std::string text) {
    Json j;
    j.v_ = Raw{std::move(text)};
    return j;
  }

  Json& operator[](const std::string& key);  // object member, created on first use
  void push(Json value);                     // array element
  std::string dump(int indent = 2) const;
  // Where the tree holds a NaN or inf number ("a.b[2].c"), in order. A value that is not
  // defined is written as Json() (null) on purpose; a non-finite number is a failed result.
  std::vector<std::string> non_finite_paths() const;

 private:
  void collect_non_finite(std::vector<std::string>& out, const std::string& at) const;
  struct Raw {
    std::string text;
  };
  void dump_to(std::string& out, int indent, int depth) const;
  std::variant<std::nullptr_t, double, bool, std::string, Object, Array, Raw> v_;
};

// ---- atomic files ------------------------------------------------------------------
// "<dir>/.<name>.partial", renamed to "<dir>/<name>" by commit.
std::string partial_name(const std::string& path);
void commit_file(const std::string& partial, const std::string& path);
void write_text_file(const std::string& path, const std::string& content);
// summary.json, refused (PhysicsError naming the quantities, nothing written) when any number
// in it is NaN or inf: a failed result must never look like a finished run. `tables` names
// top-level members whose cells may be NaN by convention (a column that does not apply to a
// row, written as null); everything else must be finite.
void write_summary(const std::string& path, const Json& summary,
                   const std::vector<std::string>& tables = {});
void make_directories(const std::string& dir);

// ---- HDF5 --------------------------------------------------------------------------
// An HDF5 file that is whole or absent: built in memory (so it costs its size in memory
// until commit), written to a hidden partial name, flushed to the device and renamed.
class H5Writer {
 public:
  explicit H5Writer(std::string path);  // writes to partial_name(path)
  ~H5Writer();                          // removes the partial file unless committed
  H5Writer(const H5Writer&) = delete;
  H5Writer& operator=(const H5Writer&) = delete;

  // Dataset "group/sub/name"; groups are created on demand. dims empty = 1-D of data.size().
  void write(const std::string& name, const std::vector<double>& data,
             std::vector<hsize_t> dims = {});
  void write(const std::string& name, const std::vector<int>& data, std::vector<hsize_t> dims = {});
  void attribute(const std::string& object, const std::string& name, double value);
  void attribute(const std::string& object, const std::string& name, const std::string& value);
  void attribute(const std::string& object, const std::string& name,
                 const std::vector<int>& values);
  void attribute_int(const std::string& object, const std::string& name, int value);
  // A variable-length UTF-8 string (h5py reads it as str; the other string attributes are
  // fixed-length ASCII, which h5py reads as bytes): what H5MD readers expect of units.
  void attribute_utf8(const std::string& object, const std::string& name, const std::string& value);
  void attribute(const std::string& object, const std::string& name,
                 const std::vector<std::string>& values);
  // A time series: `row` (of shape row_dims; empty: a scalar) becomes the next entry along a
  // first, growing dimension of dataset `name` (chunked, created by the first call).
  void append(const std::string& name, const std::vector<double>& row,
              std::vector<hsize_t> row_dims = {});
  void append(const std::string& name, const std::vector<int>& row,
              std::vector<hsize_t> row_dims = {});
  void append(const std::string& name, const std::vector<long>& row,
              std::vector<hsize_t> row_dims = {});
  void commit();  // close and rename into place

 private:
  hid_t group_for(const std::string& dataset_name);
  void write_raw(const std::string& name, hid_t type, const void* data, std::vector<hsize_t> dims);
  void append_raw(const std::string& name, hid_t type, const void* data, size_t count,
                  std::vector<hsize_t> row_dims);
  void attribute_raw(const std::string& object, const std::string& name, hid_t type, hid_t space,
                     const void* data);
  std::string path_, partial_;
  hid_t file_ = -1;
  int fd_ = -1;  // the partial file, written by commit()
  bool committed_ = false;
};

class H5Reader {
 public:
  explicit H5Reader(const std::string& path);
  ~H5Reader();
  H5Reader(const H5Reader&) = delete;
  H5Reader& operator=(const H5Reader&) = delete;
  bool has(const std::string& name) const;
  std::vector<double> reals(const std::string& name) const;
  std::vector<int> ints(const std::string& name) const;
  double attribute(const std::string& object, const std::string& name) const;
  // A scalar string attribute (fixed or variable length, trailing spaces dropped); empty
  // where the object or the attribute is absent or is not one string.
  std::string text_attribute(const std::string& object, const std::string& name) const;

 private:
  std::string path_;
  hid_t file_ = -1;
};

// Runs the Python script at `path` with Debian's python3 and `args`; returns whether it ran
// and exited with 0. A missing interpreter or script, or a failing script, is reported (`what`
// names the product in the note: "charts", "report"), not fatal: the data is kept.
// Which scripts the scenes use, and where they live: scenarios/common/charts.hpp.
bool run_python_script(const std::string& path, const std::vector<std::string>& args,
                       const std::string& what);

}  // namespace granular
