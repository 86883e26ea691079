// Atomic output files, JSON, HDF5 (see output.hpp).
#include "core/io/output.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/run/error.hpp"

namespace granular {
namespace fs = std::filesystem;

// ---- JSON --------------------------------------------------------------------------
Json::Json(const std::vector<double>& a) : v_(Array{}) {
  for (double d : a) std::get<Array>(v_).emplace_back(d);
}

Json& Json::operator[](const std::string& key) {
  if (std::holds_alternative<std::nullptr_t>(v_)) v_ = Object{};
  auto& obj = std::get<Object>(v_);
  for (auto& [k, v] : obj)
    if (k == key) return v;
  obj.emplace_back(key, Json());
  return obj.back().second;
}

void Json::push(Json value) {
  if (std::holds_alternative<std::nullptr_t>(v_)) v_ = Array{};
  std::get<Array>(v_).push_back(std::move(value));
}

namespace {
void quote(std::string& out, const std::string& s) {
  out += '"';
  for (char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  out += '"';
}
}  // namespace

void Json::dump_to(std::string& out, int indent, int depth) const {
  const std::string pad(indent * (depth + 1), ' '), pad_end(indent * depth, ' ');
  const char* nl = indent ? "\n" : "";
  if (std::holds_alternative<std::nullptr_t>(v_)) {
    out += "null";
  } else if (auto d = std::get_if<double>(&v_)) {
    if (!std::isfinite(*d)) {
      out += "null";  // JSON has no NaN/inf
    } else {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.17g", *d);
      out += buf;
    }
  } else if (auto b = std::get_if<bool>(&v_)) {
    out += *b ? "true" : "false";
  } else if (auto s = std::get_if<std::string>(&v_)) {
    quote(out, *s);
  } else if (auto r = std::get_if<Raw>(&v_)) {
    // Scene values such as `mu = inf` are not JSON numbers: quote inf and nan tokens (with
    // their sign) outside strings so summary.json stays valid JSON.
    const std::string& t = r->text;
    auto special = [&t](size_t i) -> size_t {  // length of an inf/nan token at i, or 0
      const size_t sign = (t[i] == '-' || t[i] == '+') ? 1 : 0;
      for (const char* word : {"inf", "nan"})
        if (t.compare(i + sign, 3, word) == 0 &&
            (i + sign + 3 == t.size() ||
             !std::isalnum(static_cast<unsigned char>(t[i + sign + 3]))))
          return sign + 3;
      return 0;
    };
    bool in_string = false;
    for (size_t i = 0; i < t.size(); ++i) {
      if (t[i] == '"' && (i == 0 || t[i - 1] != '\\')) in_string = !in_string;
      const size_t len = in_string ? 0 : special(i);
      if (len > 0) {
        out += '"' + t.substr(i, len) + '"';
        i += len - 1;
      } else {
        out += t[i];
      }
    }
  } else if (auto o = std::get_if<Object>(&v_)) {
    out += "{";
    out += nl;
    for (size_t i = 0; i < o->size(); ++i) {
      out += pad;
      quote(out, (*o)[i].first);
      out += ": ";
      (*o)[i].second.dump_to(out, indent, depth + 1);
      if (i + 1 < o->size()) out += ",";
      out += nl;
    }
    out += pad_end + "}";
  } else if (auto a = std::get_if<Array>(&v_)) {
    // Arrays of numbers stay on one line: they are series, not structure.
    out += "[";
    for (size_t i = 0; i < a->size(); ++i) {
      (*a)[i].dump_to(out, indent, depth + 1);
      if (i + 1 < a->size()) out += ", ";
    }
    out += "]";
  }
}

std::vector<std::string> Json::non_finite_paths() const {
  std::vector<std::string> out;
  collect_non_finite(out, "");
  return out;
}

void Json::collect_non_finite(std::vector<std::string>& out, const std::string& at) const {
  if (auto d = std::get_if<double>(&v_)) {
    if (!std::isfinite(*d)) out.push_back(at.empty() ? "(value)" : at);
  } else if (auto o = std::get_if<Object>(&v_)) {
    for (const auto& [k, v] : *o) v.collect_non_finite(out, at.empty() ? k : at + "." + k);
  } else if (auto a = std::get_if<Array>(&v_)) {
    for (size_t i = 0; i < a->size(); ++i)
      (*a)[i].collect_non_finite(out, at + "[" + std::to_string(i) + "]");
  }
}

std::string Json::dump(int indent) const {
  std::string out;
  dump_to(out, indent, 0);
  out += "\n";
  return out;
}

// ---- atomic files ------------------------------------------------------------------
std::string partial_name(const std::string& path) {
  fs::path p(path);
  return (p.parent_path() / ("." + p.filename().string() + ".partial")).string();
}

namespace {
// Flushes a file's (or directory's) data to the device: a rename is only as durable as the
// bytes behind it, and a crash between write-back and rename must not leave a complete-
// looking file with missing contents under the final name.
void sync_path(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0)
    throw std::runtime_error("cannot open " + path + " to flush it: " + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  // Some file systems cannot sync directories (EINVAL); the file's own data is what matters.
  if (rc != 0 && !(directory && (err == EINVAL || err == EROFS)))
    throw std::runtime_error("cannot flush " + path + " to disk: " + std::strerror(err));
}
}  // namespace

void commit_file(const std::string& partial, const std::string& path) {
  try {
    sync_path(partial, false);
  } catch (...) {
    std::remove(partial.c_str());  // the previous complete file, if any, stays in place
    throw;
  }
  std::error_code ec;
  fs::rename(partial, path, ec);
  if (ec) {
    std::remove(partial.c_str());
    throw std::runtime_error("cannot rename " + partial + " to " + path + ": " + ec.message());
  }
  const fs::path dir = fs::path(path).parent_path();
  sync_path(dir.empty() ? "." : dir.string(), true);
}

void make_directories(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError("cannot create output directory " + dir + ": " + ec.message());
}

void write_text_file(const std::string& path, const std::string& content) {
  const std::string tmp = partial_name(path);
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw std::runtime_error("cannot write " + tmp + ": " + std::strerror(errno));
    f << content;
    f.flush();
    f.close();
    if (!f) {
      std::remove(tmp.c_str());
      throw std::runtime_error("write failed (disk full?): " + tmp);
    }
  }
  commit_file(tmp, path);
}

void write_summary(const std::string& path, const Json& summary,
                   const std::vector<std::string>& tables) {
  std::vector<std::string> bad;
  for (const std::string& at : summary.non_finite_paths()) {
    bool in_table = false;
    for (const std::string& t : tables)
      in_table = in_table || at.compare(0, t.size() + 1, t + ".") == 0 ||
                 at.compare(0, t.size() + 1, t + "[") == 0;
    if (!in_table) bad.push_back(at);
  }
  if (!bad.empty()) {
    std::string list;
    for (size_t i = 0; i < bad.size() && i < 8; ++i) list += (i ? ", " : "") + bad[i];
    if (bad.size() > 8) list += ", ... (" + std::to_string(bad.size()) + " in all)";
    throw PhysicsError("non-finite result (NaN or inf) in " + list + ": the run failed, so " +
                       path + " was not written; look for the first warning above, or reduce" +
                       " the time step");
  }
  write_text_file(path, summary.dump());
}

// ---- HDF5 --------------------------------------------------------------------------
namespace {
// Every HDF5 call's result is checked here and turned into an error that names the file
// (and a reader asking for an optional dataset is not an error at all), so the library's
// own error-stack dump would only repeat it. Switched off once, before the first file.
void own_hdf5_errors() {
  static const bool done = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)done;
}

// Every HDF5 file the engine writes starts with a user block (HDF5 skips it; h5py, ParaView
// and h5dump read the file as usual) holding a checksum of all the bytes after it. The
// default file format checksums neither metadata nor data, so a damaged byte would otherwise
// be read as another number, a changed extent or a wrong attribute without any error (a
// checkpoint resuming with other results). FNV-1a, 64 bits: to detect damage, not tampering.
constexpr size_t kUserBlock = 512;
const char kChecksumTag[] = "granular checksummed HDF5 file\nfnv1a64 ";

uint64_t fnv1a64(const char* data, size_t n, uint64_t h = 0xcbf29ce484222325ull) {
  for (size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 0x100000001b3ull;
  }
  return h;
}

std::string checksum_line(uint64_t hash, uint64_t bytes) {
  char line[64];
  std::snprintf(line, sizeof line, "%016llx bytes %llu\n", static_cast<unsigned long long>(hash),
                static_cast<unsigned long long>(bytes));
  return std::string(kChecksumTag) + line;
}

// A file that starts with the tag must match its checksum; files without it (written before
// the checksum, or by other tools) are read as they are.
void verify_checksum(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return;  // H5Fopen names the problem
  std::string head(kUserBlock, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  if (in.gcount() < static_cast<std::streamsize>(sizeof kChecksumTag - 1) ||
      head.compare(0, sizeof kChecksumTag - 1, kChecksumTag) != 0)
    return;
  uint64_t hash = 0xcbf29ce484222325ull, bytes = 0;
  std::vector<char> buffer(1 << 20);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const size_t got = static_cast<size_t>(in.gcount());
    hash = fnv1a64(buffer.data(), got, hash);
    bytes += got;
  }
  const std::string expected = checksum_line(hash, bytes);
  if (head.compare(0, expected.size(), expected) != 0 ||
      head.find_first_not_of('\0', expected.size()) != std::string::npos)
    throw InputError("HDF5 file " + path +
                     " is damaged: its checksum does not match its contents (a byte changed on"
                     " disk or in a copy, or the file was cut short); use an intact copy");
}
}  // namespace

H5Writer::H5Writer(std::string path) : path_(std::move(path)), partial_(partial_name(path_)) {
  own_hdf5_errors();
  // The partial file is created now, so that an unwritable place fails before the run.
  fd_ = ::open(partial_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::runtime_error("cannot create HDF5 file " + partial_ + ": " + std::strerror(errno));
  // The file itself is built in memory (HDF5's core driver, no backing store) and written
  // out by commit(): HDF5 never writes to disk, so a full disk is one checked write() here,
  // never a file the library failed to close (Debian's HDF5 then crashes at exit, in its
  // clean-up of that file).
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl < 0 || H5Pset_fapl_core(fapl, 1 << 20, 0) < 0) {
    if (fapl >= 0) H5Pclose(fapl);
    throw std::runtime_error("cannot set up the in-memory HDF5 file for " + partial_);
  }
  const hid_t fcpl = H5Pcreate(H5P_FILE_CREATE);
  if (fcpl < 0 || H5Pset_userblock(fcpl, kUserBlock) < 0) {
    if (fcpl >= 0) H5Pclose(fcpl);
    H5Pclose(fapl);
    throw std::runtime_error("cannot set up the checksum block of " + partial_);
  }
  file_ = H5Fcreate(partial_.c_str(), H5F_ACC_TRUNC, fcpl, fapl);
  H5Pclose(fcpl);
  H5Pclose(fapl);
  if (file_ < 0) throw std::runtime_error("cannot create HDF5 file " + partial_);
}

H5Writer::~H5Writer() {
  if (file_ >= 0) H5Fclose(file_);  // in memory: nothing reaches the disk
  if (fd_ >= 0) ::close(fd_);
  if (!committed_) std::remove(partial_.c_str());
}

hid_t H5Writer::group_for(const std::string& name) {
  // Create intermediate groups; returns the file handle (paths are absolute from root).
  size_t pos = 0;
  while ((pos = name.find('/', pos + 1)) != std::string::npos) {
    const std::string g = name.substr(0, pos);
    if (H5Lexists(file_, g.c_str(), H5P_DEFAULT) <= 0) {
      hid_t gid = H5Gcreate2(file_, g.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
      if (gid < 0) throw std::runtime_error("cannot create HDF5 group " + g + " in " + partial_);
      H5Gclose(gid);
    }
  }
  return file_;
}

void H5Writer::write_raw(const std::string& name, hid_t type, const void* data,
                         std::vector<hsize_t> dims) {
  hid_t loc = group_for(name);
  hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  hid_t set = H5Dcreate2(loc, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (set < 0) {
    H5Sclose(space);
    throw std::runtime_error("cannot create dataset " + name + " in " + partial_);
  }
  herr_t st = H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  H5Dclose(set);
  H5Sclose(space);
  if (st < 0) throw std::runtime_error("cannot write dataset " + name + " in " + partial_);
}

void H5Writer::write(const std::string& name, const std::vector<double>& data,
                     std::vector<hsize_t> dims) {
  if (dims.empty()) dims = {data.size()};
  write_raw(name, H5T_NATIVE_DOUBLE, data.data(), dims);
}

void H5Writer::write(const std::string& name, const std::vector<int>& data,
                     std::vector<hsize_t> dims) {
  if (dims.empty()) dims = {data.size()};
  write_raw(name, H5T_NATIVE_INT, data.data(), dims);
}

void H5Writer::attribute_raw(const std::string& object, const std::string& name, hid_t type,
                             hid_t space, const void* data) {
  if (object != "/") group_for(object + "/x");
  hid_t attr = H5Acreate_by_name(file_, object.c_str(), name.c_str(), type, space, H5P_DEFAULT,
                                 H5P_DEFAULT, H5P_DEFAULT);
  const herr_t st = attr < 0 ? -1 : H5Awrite(attr, type, data);
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  if (st < 0)
    throw std::runtime_error("cannot write attribute " + object + "@" + name + " in " + partial_);
}

void H5Writer::attribute(const std::string& object, const std::string& name, double value) {
  attribute_raw(object, name, H5T_NATIVE_DOUBLE, H5Screate(H5S_SCALAR), &value);
}

void H5Writer::attribute(const std::string& object, const std::string& name,
                         const std::string& value) {
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.size() + 1);
  try {
    attribute_raw(object, name, type, H5Screate(H5S_SCALAR), value.c_str());
  } catch (...) {
    H5Tclose(type);
    throw;
  }
  H5Tclose(type);
}

void H5Writer::attribute(const std::string& object, const std::string& name,
                         const std::vector<int>& values) {
  const hsize_t n = values.size();
  attribute_raw(object, name, H5T_NATIVE_INT, H5Screate_simple(1, &n, nullptr), values.data());
}

void H5Writer::attribute_utf8(const std::string& object, const std::string& name,
                              const std::string& value) {
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  const char* text = value.c_str();
  try {
    attribute_raw(object, name, type, H5Screate(H5S_SCALAR), &text);
  } catch (...) {
    H5Tclose(type);
    throw;
  }
  H5Tclose(type);
}

void H5Writer::attribute_int(const std::string& object, const std::string& name, int value) {
  attribute_raw(object, name, H5T_NATIVE_INT, H5Screate(H5S_SCALAR), &value);
}

void H5Writer::attribute(const std::string& object, const std::string& name,
                         const std::vector<std::string>& values) {
  // Fixed-length strings, each padded to the longest (as h5py writes a list of str).
  size_t width = 1;
  for (const std::string& v : values) width = std::max(width, v.size() + 1);
  std::vector<char> packed(width * values.size(), '\0');
  for (size_t k = 0; k < values.size(); ++k)
    std::copy(values[k].begin(), values[k].end(), packed.begin() + static_cast<long>(k * width));
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, width);
  const hsize_t n = values.size();
  try {
    attribute_raw(object, name, type, H5Screate_simple(1, &n, nullptr), packed.data());
  } catch (...) {
    H5Tclose(type);
    throw;
  }
  H5Tclose(type);
}

void H5Writer::append_raw(const std::string& name, hid_t type, const void* data, size_t count,
                          std::vector<hsize_t> row_dims) {
  hsize_t row = 1;
  for (hsize_t d : row_dims) row *= d;
  if (row != count)
    throw std::runtime_error("time series " + name + ": a row of " + std::to_string(count) +
                             " values for a shape of " + std::to_string(row));
  std::vector<hsize_t> dims = {0}, max = {H5S_UNLIMITED}, chunk = {1};
  for (hsize_t d : row_dims) dims.push_back(d), max.push_back(d), chunk.push_back(d);
  hid_t set = -1;
  if (H5Lexists(group_for(name), name.c_str(), H5P_DEFAULT) > 0) {
    set = H5Dopen2(file_, name.c_str(), H5P_DEFAULT);
  } else {
    hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), max.data());
    hid_t plist = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(plist, static_cast<int>(chunk.size()), chunk.data());
    set = H5Dcreate2(file_, name.c_str(), type, space, H5P_DEFAULT, plist, H5P_DEFAULT);
    H5Pclose(plist);
    H5Sclose(space);
  }
  if (set < 0) throw std::runtime_error("cannot create time series " + name + " in " + partial_);
  hid_t space = H5Dget_space(set);
  std::vector<hsize_t> now(dims.size());
  H5Sget_simple_extent_dims(space, now.data(), nullptr);
  H5Sclose(space);
  std::vector<hsize_t> grown = now, start(dims.size(), 0), shape = dims;
  grown[0] += 1;
  start[0] = now[0];
  shape[0] = 1;
  herr_t st = H5Dset_extent(set, grown.data());
  hid_t file_space = H5Dget_space(set);
  hid_t mem_space = H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr);
  if (st >= 0)
    st = H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start.data(), nullptr, shape.data(),
                             nullptr);
  if (st >= 0) st = H5Dwrite(set, type, mem_space, file_space, H5P_DEFAULT, data);
  H5Sclose(mem_space);
  H5Sclose(file_space);
  H5Dclose(set);
  if (st < 0) throw std::runtime_error("cannot extend time series " + name + " in " + partial_);
}

void H5Writer::append(const std::string& name, const std::vector<double>& row,
                      std::vector<hsize_t> row_dims) {
  append_raw(name, H5T_NATIVE_DOUBLE, row.data(), row.size(), std::move(row_dims));
}

void H5Writer::append(const std::string& name, const std::vector<int>& row,
                      std::vector<hsize_t> row_dims) {
  append_raw(name, H5T_NATIVE_INT, row.data(), row.size(), std::move(row_dims));
}

void H5Writer::append(const std::string& name, const std::vector<long>& row,
                      std::vector<hsize_t> row_dims) {
  append_raw(name, H5T_NATIVE_LONG, row.data(), row.size(), std::move(row_dims));
}

void H5Writer::commit() {
  // The finished image, written with checked writes; any failure (full disk, I/O error)
  // removes the partial file and keeps whatever complete file had the name before.
  auto fail = [&](const std::string& why) {
    if (file_ >= 0) H5Fclose(file_);
    file_ = -1;
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    std::remove(partial_.c_str());
    throw std::runtime_error("cannot complete HDF5 file " + partial_ + " (" + why + "); " + path_ +
                             " was left as it was");
  };
  if (H5Fflush(file_, H5F_SCOPE_GLOBAL) < 0) fail("flush of the in-memory file failed");
  const ssize_t size = H5Fget_file_image(file_, nullptr, 0);
  if (size < 0) fail("no file image");
  std::vector<char> image(static_cast<size_t>(size));
  if (H5Fget_file_image(file_, image.data(), image.size()) != size) fail("no file image");
  const herr_t closed = H5Fclose(file_);
  file_ = -1;
  if (closed < 0) fail("close of the in-memory file failed");
  // The image holds the file from its superblock on: the user block HDF5 reserved in front of
  // it (the superblock's base address) is written here, and carries the image's checksum.
  std::string block = checksum_line(fnv1a64(image.data(), image.size()), image.size());
  block.resize(kUserBlock, '\0');
  image.insert(image.begin(), block.begin(), block.end());
  size_t done = 0;
  while (done < image.size()) {
    const ssize_t n = ::write(fd_, image.data() + done, image.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(std::string("write failed: ") + std::strerror(n < 0 ? errno : ENOSPC));
    done += static_cast<size_t>(n);
  }
  if (::close(fd_) != 0) {
    fd_ = -1;
    fail(std::string("close failed: ") + std::strerror(errno));
  }
  fd_ = -1;
  commit_file(partial_, path_);
  committed_ = true;
}

H5Reader::H5Reader(const std::string& path) : path_(path) {
  own_hdf5_errors();
  verify_checksum(path);
  file_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file_ < 0) throw InputError("cannot open HDF5 file " + path);
}
H5Reader::~H5Reader() {
  if (file_ >= 0) H5Fclose(file_);
}

bool H5Reader::has(const std::string& name) const {
  // Check each path component, as H5Lexists requires.
  size_t pos = 0;
  while (true) {
    pos = name.find('/', pos + 1);
    const std::string part = name.substr(0, pos);
    if (H5Lexists(file_, part.c_str(), H5P_DEFAULT) <= 0) return false;
    if (pos == std::string::npos) return true;
  }
}

namespace {
template <class T>
std::vector<T> read_all(hid_t file, const std::string& path, const std::string& name, hid_t type) {
  hid_t set = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  if (set < 0) throw InputError("HDF5 file " + path + " has no dataset " + name);
  hid_t space = H5Dget_space(set);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  // An uncompressed (contiguous or compact) dataset that declares more data than the file
  // holds is damaged, and allocating its size would only end in bad_alloc; a chunked one may
  // be compressed, so it is allowed a thousand times the file's size.
  hsize_t file_bytes = 0;
  H5Fget_filesize(file, &file_bytes);
  const hid_t plist = H5Dget_create_plist(set);
  const bool chunked = plist >= 0 && H5Pget_layout(plist) == H5D_CHUNKED;
  if (plist >= 0) H5Pclose(plist);
  const double room = (chunked ? 1000.0 : 1.0) * static_cast<double>(file_bytes) + 4096.0;
  if (n < 0 || static_cast<double>(n) * sizeof(T) > room) {
    H5Sclose(space);
    H5Dclose(set);
    throw InputError("HDF5 file " + path + ": dataset " + name + " declares " + std::to_string(n) +
                     " values, more than the file's " + std::to_string(file_bytes) +
                     " bytes hold (a damaged file)");
  }
  std::vector<T> out(static_cast<size_t>(n));
  herr_t st = H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
  H5Sclose(space);
  H5Dclose(set);
  if (st < 0) throw InputError("cannot read dataset " + name + " from " + path);
  return out;
}
}  // namespace

std::vector<double> H5Reader::reals(const std::string& name) const {
  return read_all<double>(file_, path_, name, H5T_NATIVE_DOUBLE);
}
std::vector<int> H5Reader::ints(const std::string& name) const {
  return read_all<int>(file_, path_, name, H5T_NATIVE_INT);
}
double H5Reader::attribute(const std::string& object, const std::string& name) const {
  double v = 0;
  hid_t attr = H5Aopen_by_name(file_, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  if (attr < 0) throw InputError("HDF5 file " + path_ + " lacks attribute " + object + "@" + name);
  const herr_t st = H5Aread(attr, H5T_NATIVE_DOUBLE, &v);
  H5Aclose(attr);
  if (st < 0)
    throw InputError("cannot read attribute " + object + "@" + name + " from " + path_ +
                     " as a number");
  return v;
}

std::string H5Reader::text_attribute(const std::string& object, const std::string& name) const {
  std::string text;
  H5E_BEGIN_TRY {
    if (H5Aexists_by_name(file_, object.c_str(), name.c_str(), H5P_DEFAULT) > 0) {
      const hid_t a =
          H5Aopen_by_name(file_, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
      const hid_t t = a >= 0 ? H5Aget_type(a) : -1;
      const hid_t sp = a >= 0 ? H5Aget_space(a) : -1;
      if (t >= 0 && sp >= 0 && H5Tget_class(t) == H5T_STRING &&
          H5Sget_simple_extent_npoints(sp) == 1) {
        if (H5Tis_variable_str(t) > 0) {
          const hid_t m = H5Tcopy(H5T_C_S1);
          H5Tset_size(m, H5T_VARIABLE);
          H5Tset_cset(m, H5Tget_cset(t));
          char* value = nullptr;
          if (H5Aread(a, m, &value) >= 0 && value) text = value;
          if (value) H5free_memory(value);
          H5Tclose(m);
        } else {
          std::vector<char> value(H5Tget_size(t) + 1, '\0');
          if (H5Aread(a, t, value.data()) >= 0) text = value.data();
        }
      }
      if (sp >= 0) H5Sclose(sp);
      if (t >= 0) H5Tclose(t);
      if (a >= 0) H5Aclose(a);
    }
  }
  H5E_END_TRY;
  const size_t end = text.find_last_not_of(' ');  // space-padded fixed-length strings
  return end == std::string::npos ? std::string() : text.substr(0, end + 1);
}

// ---- Python scripts ----------------------------------------------------------------
bool run_python_script(const std::string& path, const std::vector<std::string>& args,
                       const std::string& what) {
  const std::string python = "/usr/bin/python3";
  if (!fs::exists(python) || !fs::exists(path)) {
    std::cerr << "note: " << what << " skipped (" << (fs::exists(python) ? path : python)
              << " not found)\n";
    return false;
  }
  // The interpreter is started directly with an argument vector: paths reach it as they are,
  // whatever quotes or shell syntax they hold (no shell ever parses them).
  std::vector<std::string> all = {python, path};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::cout.flush();
  std::cerr.flush();
  pid_t pid = -1;
  int rc = ::posix_spawn(&pid, python.c_str(), nullptr, nullptr, argv.data(), environ);
  if (rc == 0) {
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    rc = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  if (rc != 0) {
    std::cerr << "warning: " << what << " script " << path << " failed (exit " << rc << ")\n";
    return false;
  }
  return true;
}

}  // namespace granular
