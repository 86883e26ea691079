// The processes one run is spread over. A scene's independent units (chain realizations in
// blocks, tone experiments, preparation variants, mixtures) are dealt to the ranks of an
// MPI launch (`mpirun -np R granular run ...`); every rank computes its units with its own
// threads, and rank 0 gathers the results in unit order and writes every output, so the
// files do not depend on R. A process not started by an MPI launcher (or a build without
// MPI) is one rank and never touches MPI.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace granular {

namespace ensemble {

// MPI_Init when the process was started by an MPI launcher (its environment says so),
// nothing otherwise. Call before Kokkos::initialize.
void initialize(int* argc, char*** argv);
void finalize();  // after Kokkos::finalize
int rank();
int size();
inline bool root() { return rank() == 0; }
// This rank's index among the ranks on its machine (from the launcher), for choosing a GPU.
int local_rank();
// "rank r: " in a run of several ranks (for messages and progress lines), "" otherwise.
std::string prefix();
// Writes `line` (a newline is added) to standard error in one write: a rank's message is
// never cut by another process's output (an MPI launcher's abort banner) landing between
// its pieces.
void say(const std::string& line);
bool built_with_mpi();
// Ends every rank of the run at once (MPI_Abort), so that one rank's failure never leaves
// the others waiting for it; a single process just exits.
[[noreturn]] void abort_all(int code);
void barrier();
// Rank 0 receives every rank's bytes in rank order (its own first); other ranks get {}.
std::vector<std::string> gather(const std::string& bytes);
// Rank 0's bytes, on every rank.
std::string broadcast(const std::string& bytes);
// True on every rank when `flag` is true on any rank.
bool any(bool flag);

// The contiguous share [first, last) of n units that `rank` of `ranks` runs: whole units,
// the first n % ranks ranks one more.
std::pair<std::size_t, std::size_t> share(std::size_t n, int rank, int ranks);
inline std::pair<std::size_t, std::size_t> my_share(std::size_t n) {
  return share(n, rank(), size());
}

// Rank 0 gets a copy, at the same path, of every file the ranks list (each rank its own),
// written to a temporary name and renamed; a file rank 0 already holds with the same bytes
// is left as it is (ranks that share a file system). Collective.
void collect_files(const std::vector<std::string>& paths);

}  // namespace ensemble

// Bytes of numbers and text, for what ranks send each other; read back in the same order.
class Packer {
 public:
  Packer& put(double x);
  Packer& put(std::int64_t x);
  Packer& put(const std::vector<double>& x);
  Packer& put(const std::string& x);
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

class Unpacker {
 public:
  explicit Unpacker(const std::string& bytes) : bytes_(bytes) {}
  double real();
  std::int64_t integer();
  std::vector<double> reals();
  std::string text();
  bool done() const { return at_ == bytes_.size(); }

 private:
  void take(void* out, std::size_t n);
  const std::string& bytes_;
  std::size_t at_ = 0;
};

}  // namespace granular
