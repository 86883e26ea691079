// Ranks of a run (see ensemble.hpp). Point-to-point messages in chunks below 1 GiB carry
// blobs of any size; rank 0 always receives in rank order, never in arrival order.
#include "core/run/ensemble.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <stdexcept>

#include "core/io/output.hpp"

#ifdef GRANULAR_HAVE_MPI
// The C interface only (Open MPI's header would pull in its deprecated C++ bindings).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace granular {

namespace ensemble {

namespace {
int g_rank = 0, g_size = 1;

#ifdef GRANULAR_HAVE_MPI
bool g_mpi = false;  // MPI_Init was called
constexpr std::size_t kChunk = std::size_t(1) << 30;

void send_bytes(const std::string& b, int to) {
  std::uint64_t n = b.size();
  MPI_Send(&n, 1, MPI_UINT64_T, to, 1, MPI_COMM_WORLD);
  for (std::size_t at = 0; at < b.size(); at += kChunk) {
    const int len = static_cast<int>(std::min(kChunk, b.size() - at));
    MPI_Send(b.data() + at, len, MPI_CHAR, to, 2, MPI_COMM_WORLD);
  }
}

std::string receive_bytes(int from) {
  std::uint64_t n = 0;
  MPI_Recv(&n, 1, MPI_UINT64_T, from, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  std::string b(n, '\0');
  for (std::size_t at = 0; at < b.size(); at += kChunk) {
    const int len = static_cast<int>(std::min<std::size_t>(kChunk, b.size() - at));
    MPI_Recv(b.data() + at, len, MPI_CHAR, from, 2, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  }
  return b;
}

// Launchers announce themselves in the environment (Open MPI, PMIx, MPICH's Hydra, Slurm's
// PMI): only then is MPI initialized, so a plain run never starts MPI's runtime.
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"})
    if (std::getenv(v)) return true;
  return false;
}
#endif

}  // namespace

bool built_with_mpi() {
#ifdef GRANULAR_HAVE_MPI
  return true;
#else
  return false;
#endif
}

void initialize(int* argc, char*** argv) {
#ifdef GRANULAR_HAVE_MPI
  if (!launched_by_mpi()) return;
  int provided = 0;
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  g_mpi = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_size);
#else
  (void)argc, (void)argv;
  const char* n = std::getenv("OMPI_COMM_WORLD_SIZE");
  if (!n) n = std::getenv("PMI_SIZE");
  if (n && std::atoi(n) > 1) {
    std::cerr << "error: started by an MPI launcher with " << n
              << " ranks, but this build has no MPI: every rank would run the whole scene "
                 "and write the same files. Install OpenMPI (scripts/setup.sh does by "
                 "default) and build again, or run without mpirun\n";
    std::exit(2);
  }
#endif
}

void finalize() {
#ifdef GRANULAR_HAVE_MPI
  if (g_mpi) MPI_Finalize();
  g_mpi = false;
#endif
}

int rank() { return g_rank; }
std::string prefix() { return g_size > 1 ? "rank " + std::to_string(g_rank) + ": " : ""; }

void say(const std::string& line) {
  std::cerr.flush();
  const std::string text = line + "\n";
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(2, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += static_cast<size_t>(n);
  }
}
int local_rank() {
  for (const char* v : {"OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID", "SLURM_LOCALID"})
    if (const char* x = std::getenv(v)) return std::atoi(x);
  return 0;
}
int size() { return g_size; }

void abort_all(int code) {
#ifdef GRANULAR_HAVE_MPI
  if (g_mpi && g_size > 1) {
    std::cerr.flush();
    MPI_Abort(MPI_COMM_WORLD, code);
  }
#endif
  std::exit(code);
}

void barrier() {
#ifdef GRANULAR_HAVE_MPI
  if (g_mpi) MPI_Barrier(MPI_COMM_WORLD);
#endif
}

std::vector<std::string> gather(const std::string& bytes) {
  std::vector<std::string> out;
  if (g_size == 1) return {bytes};
#ifdef GRANULAR_HAVE_MPI
  if (g_rank == 0) {
    out.push_back(bytes);
    for (int r = 1; r < g_size; ++r) out.push_back(receive_bytes(r));
  } else {
    send_bytes(bytes, 0);
  }
#endif
  return out;
}

std::string broadcast(const std::string& bytes) {
  if (g_size == 1) return bytes;
  std::string b = g_rank == 0 ? bytes : std::string();
#ifdef GRANULAR_HAVE_MPI
  if (g_rank == 0) {
    for (int r = 1; r < g_size; ++r) send_bytes(b, r);
  } else {
    b = receive_bytes(0);
  }
#endif
  return b;
}

bool any(bool flag) {
  if (g_size == 1) return flag;
  int in = flag ? 1 : 0, out = in;
#ifdef GRANULAR_HAVE_MPI
  MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
#endif
  return out != 0;
}

std::pair<std::size_t, std::size_t> share(std::size_t n, int r, int ranks) {
  const std::size_t q = n / ranks, extra = n % ranks, ur = static_cast<std::size_t>(r);
  const std::size_t first = ur * q + std::min(ur, extra);
  return {first, first + q + (ur < extra ? 1 : 0)};
}

void collect_files(const std::vector<std::string>& paths) {
  if (g_size == 1) return;
  Packer p;
  p.put(static_cast<std::int64_t>(paths.size()));
  for (const std::string& path : paths) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + path + " to send it to rank 0");
    p.put(path).put(std::string(std::istreambuf_iterator<char>(in), {}));
  }
  const std::vector<std::string> all = gather(p.bytes());
  for (std::size_t r = 1; r < all.size(); ++r) {
    Unpacker u(all[r]);
    const std::int64_t n = u.integer();
    for (std::int64_t i = 0; i < n; ++i) {
      const std::string path = u.text(), content = u.text();
      std::ifstream have(path, std::ios::binary);
      if (have && std::string(std::istreambuf_iterator<char>(have), {}) == content) continue;
      make_directories(std::filesystem::path(path).parent_path().string());
      write_text_file(path, content);  // temporary name, then renamed
    }
  }
}

}  // namespace ensemble

Packer& Packer::put(double x) {
  bytes_.append(reinterpret_cast<const char*>(&x), sizeof x);
  return *this;
}
Packer& Packer::put(std::int64_t x) {
  bytes_.append(reinterpret_cast<const char*>(&x), sizeof x);
  return *this;
}
Packer& Packer::put(const std::vector<double>& x) {
  put(static_cast<std::int64_t>(x.size()));
  bytes_.append(reinterpret_cast<const char*>(x.data()), x.size() * sizeof(double));
  return *this;
}
Packer& Packer::put(const std::string& x) {
  put(static_cast<std::int64_t>(x.size()));
  bytes_.append(x);
  return *this;
}

void Unpacker::take(void* out, std::size_t n) {
  if (at_ + n > bytes_.size()) throw std::runtime_error("a message between ranks is truncated");
  std::memcpy(out, bytes_.data() + at_, n);
  at_ += n;
}
double Unpacker::real() {
  double x;
  take(&x, sizeof x);
  return x;
}
std::int64_t Unpacker::integer() {
  std::int64_t x;
  take(&x, sizeof x);
  return x;
}
std::vector<double> Unpacker::reals() {
  std::vector<double> x(static_cast<std::size_t>(integer()));
  if (!x.empty()) take(x.data(), x.size() * sizeof(double));
  return x;
}
std::string Unpacker::text() {
  std::string x(static_cast<std::size_t>(integer()), '\0');
  if (!x.empty()) take(x.data(), x.size());
  return x;
}

}  // namespace granular
