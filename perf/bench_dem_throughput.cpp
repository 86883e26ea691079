// DEM step throughput (particle-steps per second) on dense packings (phi ~ 0.64), with a
// per-phase profile, the bytes a step moves and the fraction of the memory bandwidth
// measured in the same run. Thread count comes from --kokkos-threads; run once per count.
//
//   bench_dem_throughput --kokkos-threads=2 [--sizes 4096,32768] [--reps 3] [--steps 2000]
//                        [--physics frictionless,friction,...|all] [--data packing.data]
//                        [--out perf/results/dem_throughput_2t.json] [--no-triad] [--no-batch]
//                        [--near-skin S]
//                        [--alternate batch|near|stream|skin|rows|pack [--block B]]
//                        [--skin-b S] [--zero-rows] [--no-pack] [--pack-min N]
//                        [--thread-per-particle] [--slabs S] [--block-rows R]
//                        [--tile NX,NY,NZ] [--no-memory] [--walls] [--two-pass] [--mixed]
// --no-batch evaluates frictional contacts one by one instead of in AVX batches
// (DemParams::batched_contacts; the same bits, for before/after figures from one binary).
// --near-skin S: the force pass's near list (DemParams::near_skin: < 0, the default, a 32nd of
// the skin where the near stream reads it for the frictional law, a 16th elsewhere; 0 none;
// the same bits for any value).
// --alternate batch|near|stream [--block B]: after the timed run, steps the same trajectory in
// blocks of B steps (default 100) with the batch (the near list, the near list's stream)
// switched on and off in turn and reports the ratio of the two rates (median over the pairs of
// blocks): an A/B comparison whose two sides share the machine's slow phases, for changes
// smaller than the spread between runs. --alternate skin alternates the near skin between
// --near-skin (A) and --skin-b (B).
// --alternate rows: the two-pass kernel's flagged apart rows (A) against zero rows (B), laws
// with rotations; --zero-rows: zero rows for the whole run (DemParams::flag_apart_rows; the
// same bits).
// --alternate pack: the frictional stream reading the particles' packed records (A) against
// their arrays (B); --no-pack: the arrays for the whole run (DemParams::packed_stream; the
// same bits); --pack-min N: the records from N particles on (packed_stream_min_particles).
// --thread-per-particle: the device's contacts pass with one thread per particle instead of
// one per contact (DemParams::contact_thread_per_particle; the same bits).
// --slabs / --block-rows: the host force pass's partition and the cell order
// (DemParams::force_slabs, cell_block_rows; they change the order of the force sums).
// --tile NX,NY,NZ: the --data packing replicated NX x NY x NZ times (periodic images, same
// contacts per particle at every size); how a 100-million-sphere packing is made from the
// peer's 32768 without a file of gigabytes.
// Every row records the peak of the device allocations during its first repetition, array
// by array (perf/allocation_tracker.hpp), and a minimal-traffic model of the step beside the
// engine's own byte count (docs/gpu_memory.md); --no-memory leaves the tracking out.
// --walls: the box's z faces are planar walls with the pair's own law (a wall of infinite radius
// and mass, as LAMMPS' fix wall/gran): the peer comparison's walled box (perf/peer/walls.lmp
// makes its packing from the periodic one).
// --two-pass: host backends run the device's two-pass force kernel (DemParams::two_pass_forces).
// --mixed: the force pass reads fixed-point positions (DemParams::mixed_precision, which runs the
// two-pass kernel; docs/mixed_precision.md). Rows record their "precision" and "force_kernel".
// --no-triad skips the bandwidth measurements, triad and copy (their 768 MiB of arrays would
// also dominate the peak resident memory that every row records).
// The physics options are the cost of each model switch on the same packing:
//   frictionless   linear normal spring-dashpot only (no history, no rotations)
//   friction       + tangential spring with history and Coulomb mu = 0.5, rotations
//   rolling        + rolling and torsion resistance
//   hertz_mindlin  Hertz normal + Mindlin tangential (stiffness form), mu = 0.5
//   hertz_tsuji    the restitution-damped Hertz-Mindlin law of the studies, as the peer deck's
//                  LAMMPS `granular hertz/material ... damping tsuji tangential mindlin` (below)
//   hysteretic     hysteretic adhesive normal law (k1/k2 = 0.666, kc = k2/2) + friction
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "allocation_tracker.hpp"
#include "core/io/output.hpp"
#include "core/lammps/lammps_data.hpp"
#include "core/run/error.hpp"
#include "dense_packing.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/dem_system.hpp"
#include "machine_info.hpp"
#include "scenarios/common/contact_config.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/lammps/native_laws.hpp"

using namespace granular;
using Exec = Kokkos::DefaultExecutionSpace;
using perf::bench_params;
using perf::dense_packing;

namespace {

// The benchmark's physics: the spec's linear set (k_n 1e5 N/mm, gamma_n 1000 ug/us
// absolute, k_t 8e4, gamma_t 500, mu 0.5 when frictional), no background damping,
// dt = 0.0045 us (t_c/50 of the smallest pair), skin 0.2 mm. Units mm, us, ug.
// These are the peer decks' parameters in SI: 1e8 N/m, 1 kg/s, 8e7 N/m, 0.5 kg/s.
ContactConfig physics_config(const std::string& name) {
  ContactConfig c;
  c.linear = {1e5, 1000};
  c.coulomb = {8e4, 500, 0.5, 0.5, CoulombTangential::Constant};
  if (name == "frictionless") return c;
  c.tangential = "coulomb";
  if (name == "friction") return c;
  if (name == "rolling") {
    c.rolling = true;
    c.rolling_params = {2e4, 100, 0.1, 2e4, 100, 0.1};
    return c;
  }
  if (name == "hertz_mindlin") {
    c.normal = "hertz";
    c.hertz = HertzNormal::stiffness_form(29e3, 0.2, 1000);
    c.coulomb = {2 * 29e3 / 1.8, 20, 0.5, 0.5, CoulombTangential::MindlinPairDiameter};
    return c;
  }
  if (name == "hysteretic") {
    c.normal = "hysteretic";
    c.hysteretic = {0.666e5, 1e5, 0.5e5, 1000};
    return c;
  }
  throw std::runtime_error("unknown physics '" + name +
                           "' (frictionless, friction, rolling, hertz_mindlin, hertz_tsuji, "
                           "hysteretic, all)");
}
// The peer deck's Hertz law (perf/peer/bench.lmp, model hertz_tsuji), in LAMMPS' terms and SI:
// 4/3 E* = 1e12 Pa (1e8 N/m at sqrt(delta R) = 1e-4 m, the stiffness of the linear set),
// restitution 0.9 through Tsuji's damping, Mindlin k_t = 8 G* (NULL), the tangential dashpot
// half the normal one, mu 0.5. The engine runs it as its own restitution-damped Hertz-Mindlin
// law (scenarios/lammps/native_laws.hpp), with the stresses in MPa.
constexpr const char* kHertzTsujiCoeff =
    "* * hertz/material 1.365e12 0.9 0.3 tangential mindlin NULL 0.5 0.5 damping tsuji";
NativeHertzTsuji hertz_tsuji_model() {
  const LammpsPairModel m =
      parse_lammps_pair("granular", {kHertzTsujiCoeff}, 1, lammps_units("si"));
  return native_hertz_tsuji(m.pair(1, 1), 1e-6);
}

std::vector<int> parse_sizes(const std::string& s) {
  std::vector<int> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::stoi(item));
  return out;
}

// The packing repeated t[0] x t[1] x t[2] times along the box edges (periodic images).
HostParticles tiled(const HostParticles& one, PeriodicBox& box, const std::vector<int>& t) {
  const long copies = static_cast<long>(t[0]) * t[1] * t[2];
  const long n1 = one.size();
  if (n1 * copies > 2000000000L)
    throw InputError("--tile: " + std::to_string(n1 * copies) +
                     " particles exceed the engine's 32-bit particle index");
  HostParticles out;
  out.resize(static_cast<int>(n1 * copies));
  long k = 0;
  for (int a = 0; a < t[0]; ++a)
    for (int b = 0; b < t[1]; ++b)
      for (int c = 0; c < t[2]; ++c)
        for (long i = 0; i < n1; ++i, ++k) {
          out.x[k] = one.x[i] + a * box.len[0];
          out.y[k] = one.y[i] + b * box.len[1];
          out.z[k] = one.z[i] + c * box.len[2];
          out.vx[k] = one.vx[i], out.vy[k] = one.vy[i], out.vz[k] = one.vz[i];
          out.wx[k] = one.wx[i], out.wy[k] = one.wy[i], out.wz[k] = one.wz[i];
          out.radius[k] = one.radius[i], out.density[k] = one.density[i];
          out.species[k] = one.species[i];
        }
  for (int d = 0; d < 3; ++d) box.len[d] *= t[d];
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// Every option, with its default (the comment at the top describes them).
struct BenchOptions {
  std::string sizes = "4096,32768", data, out, cache_dir = "perf_cache", physics = "frictionless";
  int reps = 3;
  bool triad = true, batched = true, per_particle = false, flagged = true, packed = true;
  std::string alternate;
  long block = 100;
  double near_skin = DemParams{}.near_skin, skin_b = 0.0;
  int slabs = DemParams{}.force_slabs, block_rows = DemParams{}.cell_block_rows;
  int pack_min = DemParams{}.packed_stream_min_particles;
  long steps = 2000, warmup = 500;
  std::vector<int> tile{1, 1, 1};
  bool track_memory = true, walls = false, two_pass = false, mixed = false;
  // Whether the force pass is the two-pass kernel (devices, or asked for on a host).
  bool rows_kernel() const { return two_pass || mixed || !forces_by_slabs<Exec>(); }
};

// Sets the option `a` when it is one that takes no value; false when it is not.
bool parse_switch(const std::string& a, BenchOptions& o) {
  if (a == "--no-triad")
    o.triad = false;
  else if (a == "--no-batch")
    o.batched = false;
  else if (a == "--no-pack")
    o.packed = false;
  else if (a == "--zero-rows")
    o.flagged = false;
  else if (a == "--thread-per-particle")
    o.per_particle = true;
  else if (a == "--no-memory")
    o.track_memory = false;
  else if (a == "--walls")
    o.walls = true;
  else if (a == "--two-pass")
    o.two_pass = true;
  else if (a == "--mixed")
    o.mixed = true;
  else
    return false;
  return true;
}

// Sets the option `a` when it is one that takes a value, which next() reads; false when it is
// not.
template <class Next>
bool parse_valued(const std::string& a, Next&& next, BenchOptions& o) {
  if (a == "--sizes")
    o.sizes = next();
  else if (a == "--reps")
    o.reps = std::stoi(next());
  else if (a == "--steps")
    o.steps = std::stol(next());
  else if (a == "--warmup")
    o.warmup = std::stol(next());
  else if (a == "--data")
    o.data = next();
  else if (a == "--physics")
    o.physics = next();
  else if (a == "--out")
    o.out = next();
  else if (a == "--cache")
    o.cache_dir = next();
  else if (a == "--alternate")
    o.alternate = next();
  else if (a == "--near-skin")
    o.near_skin = std::stod(next());
  else if (a == "--skin-b")
    o.skin_b = std::stod(next());
  else if (a == "--block")
    o.block = std::stol(next());
  else if (a == "--pack-min")
    o.pack_min = std::stoi(next());
  else if (a == "--slabs")
    o.slabs = std::stoi(next());
  else if (a == "--tile")
    o.tile = parse_sizes(next());
  else if (a == "--block-rows")
    o.block_rows = std::stoi(next());
  else
    return false;
  return true;
}

// Why the options, once read, are refused; empty when they are not.
std::string check_options(const BenchOptions& o) {
  if (o.tile.size() != 3 || *std::min_element(o.tile.begin(), o.tile.end()) < 1)
    return "--tile takes three positive counts, NX,NY,NZ";
  if (o.data.empty() && o.tile != std::vector<int>{1, 1, 1})
    return "--tile replicates the --data packing; give --data";
  const std::string& alt = o.alternate;
  if (!alt.empty() && alt != "batch" && alt != "near" && alt != "stream" && alt != "skin" &&
      alt != "rows" && alt != "pack")
    return "--alternate takes batch, near, stream, skin, rows or pack, not " + alt;
  if (o.block < 1) return "--block must be at least 1";
  return "";
}

// Reads the command line into `o` (Kokkos' own --kokkos options pass); returns the message for
// a refused command line (exit status 2), empty when it is accepted. A missing value throws.
std::string parse_options(int argc, char** argv, BenchOptions& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error("missing value after " + a);
      return argv[++i];
    };
    if (parse_switch(a, o) || parse_valued(a, next, o)) continue;
    if (a.rfind("--kokkos", 0) != 0) return "unknown option " + a;
  }
  return check_options(o);
}

// The physics names of --physics, "all" for every one.
std::vector<std::string> physics_names(const std::string& physics) {
  std::vector<std::string> physics_list;
  std::stringstream ss(physics == "all"
                           ? "frictionless,friction,rolling,hertz_mindlin,hertz_tsuji,hysteretic"
                           : physics);
  std::string item;
  while (std::getline(ss, item, ',')) physics_list.push_back(item);
  return physics_list;
}

// What every row shares: the thread count and the bandwidths measured before the rows (0
// with --no-triad).
struct BenchContext {
  int threads = 0;
  double bandwidth = 0, copy_bw = 0;
};

// The result's fields ahead of its rows: the machine and the run's settings.
Json result_header(const BenchOptions& o, const BenchContext& c) {
  Json result = Json::object();
  result["benchmark"] = "dem_throughput";
  result["machine"] = perf::machine_info();
  if (o.triad) result["triad_bandwidth_GBs"] = c.bandwidth / 1e9;
  if (o.triad) result["copy_bandwidth_GBs"] = c.copy_bw / 1e9;
  result["parameters"] =
      "k_n 1e5, gamma_n 1000, k_t 8e4, gamma_t 500, mu 0.5 (mm, us, ug); dt 0.0045, skin 0.2";
  result["steps_timed"] = o.steps;
  result["warmup_steps"] = o.warmup;
  result["batched_contacts"] = o.batched && cpu_has_avx();
  result["near_skin"] = o.near_skin;
  result["packed_stream"] = o.packed;
  result["packed_stream_min_particles"] = o.pack_min;
  result["force_slabs"] = o.slabs == 0 ? Json("automatic") : Json(o.slabs);
  result["cell_block_rows"] = o.block_rows;
  if (o.rows_kernel())
    result["contacts_pass"] = o.per_particle ? "thread per particle" : "thread per contact";
  return result;
}

// One row's packing: the particles, the box and where they come from.
struct Packing {
  HostParticles host;
  PeriodicBox box;
  std::string source;
};

// The --data packing (tiled with --tile), or a generated one of about n_req spheres; with
// --walls, its z faces closed.
Packing load_packing(const BenchOptions& o, int n_req) {
  Packing p;
  if (!o.data.empty()) {
    LammpsData d = read_lammps_data(o.data);
    if (d.triclinic())
      throw InputError(o.data + ": triclinic box (xy xz yz); the DEM box is cuboid");
    p.host = std::move(d.particles);
    for (int k = 0; k < 3; ++k) p.box.lo[k] = d.lo[k], p.box.len[k] = d.len[k];
    p.source = o.data;
    if (o.tile != std::vector<int>{1, 1, 1}) {
      p.host = tiled(p.host, p.box, o.tile);
      p.source += " tiled " + std::to_string(o.tile[0]) + "x" + std::to_string(o.tile[1]) + "x" +
                  std::to_string(o.tile[2]);
    }
  } else {
    p.host = dense_packing(n_req, p.box, o.cache_dir);
    p.source = "generated (seed 12345)";
  }
  if (o.walls) {
    if (o.tile[2] != 1) throw InputError("--walls: the packing is not tiled along z");
    p.box.periodic[2] = false;
    p.source += ", z faces closed by walls";
  }
  return p;
}

// The engine's parameters for one physics and the options.
DemParams dem_params(const BenchOptions& o, const std::string& phys) {
  DemParams prm = bench_params();
  prm.batched_contacts = o.batched;
  prm.near_skin = o.near_skin;
  prm.contact_thread_per_particle = o.per_particle;
  prm.flag_apart_rows = o.flagged;
  prm.packed_stream = o.packed;
  prm.packed_stream_min_particles = o.pack_min;
  prm.force_slabs = o.slabs, prm.cell_block_rows = o.block_rows;
  prm.two_pass_forces = o.two_pass;
  prm.mixed_precision = o.mixed;
  // The time-step guard takes a Hertz contact's stiffness at the largest overlap the
  // run allows: at the benchmark's bound (a whole radius) the deck's dt would be
  // refused. A fifth of the smallest radius is forty times the packing's overlaps.
  if (phys == "hertz_tsuji") prm.max_overlap = 0.2;
  return prm;
}

// What a row's repetitions measure: each one's rate (and --alternate ratio), the first one's
// profile, peak memory and initial state, the last one's state and counters.
struct RowMeasures {
  std::vector<double> rates, alternated;
  StepProfile prof;
  double peak_memory = 0;
  std::vector<perf::AllocationTracker::Entry> memory_at_peak;
  double z_initial = 0, ekin_initial = 0, z_start = 0, z_end = 0, phi = 0, ekin_start = 0,
         ekin_end = 0, erot_start = 0, erot_end = 0;
  long builds = 0, near_recordings = 0, near_reads = 0, packed_reads = 0;
  int slabs_used = 0;
  double entries = 0;
};

// The floor and the ceiling, outward normals, the pairs' material.
template <class System>
void close_z_faces(System& sys, const PeriodicBox& box) {
  WallSpec lo, hi;
  lo.name = "floor", hi.name = "ceiling";
  lo.normal[2] = -1.0, hi.normal[2] = 1.0;
  lo.point[2] = box.lo[2], hi.point[2] = box.lo[2] + box.len[2];
  sys.set_walls({lo, hi});
}

// The warmup, then the timed steps: their rate, the state around them and the counters.
template <class System>
void timed_window(System& sys, const BenchOptions& o, int n, RowMeasures& rm) {
  sys.step(o.warmup);
  const Measurements m0 = sys.measure();
  const long builds0 = sys.neighbor_list().builds();
  const NearListUse near0 = sys.near_list_use();
  Kokkos::fence();
  Kokkos::Timer t;
  sys.step(o.steps);
  Kokkos::fence();
  const double sec = t.seconds();
  rm.rates.push_back(static_cast<double>(n) * o.steps / sec);
  const Measurements m1 = sys.measure();
  rm.z_start = m0.z, rm.z_end = m1.z, rm.phi = m1.phi;
  rm.ekin_start = m0.ekin, rm.ekin_end = m1.ekin, rm.erot_start = m0.ekin_rot,
  rm.erot_end = m1.ekin_rot;
  rm.builds = sys.neighbor_list().builds() - builds0;
  rm.near_recordings = sys.near_list_use().recordings - near0.recordings;
  rm.near_reads = sys.near_list_use().reads - near0.reads;
  rm.packed_reads = sys.near_list_use().packed_reads - near0.packed_reads;
  rm.entries = sys.neighbor_list().num_entries();
  rm.slabs_used = sys.neighbor_list().num_slabs();
}

// The --alternate switch on (A) or off (B).
template <class System>
void set_alternated(System& sys, const BenchOptions& o, bool on) {
  if (o.alternate == "batch")
    sys.set_batched_contacts(on);
  else if (o.alternate == "stream")
    sys.set_near_stream(on);
  else if (o.alternate == "skin")
    sys.set_near_skin(on ? o.near_skin : o.skin_b);
  else if (o.alternate == "rows")
    sys.set_flag_apart_rows(on);
  else if (o.alternate == "pack")
    sys.set_packed_stream(on);
  else
    sys.set_near_skin(on ? o.near_skin : 0.0);
}

// Blocks of --block steps switched on (A) and off (B) in turn, same trajectory, then the
// options' settings back; returns the on/off rate ratio, the median over the pairs of blocks.
template <class System>
double alternate_blocks(System& sys, const BenchOptions& o, const std::string& phys, int n, int r) {
  std::vector<double> ratio;
  double t_on = 0, t_off = 0;
  for (long s = 0; s + 2 * o.block <= o.steps; s += 2 * o.block) {
    double sec[2];
    for (int side = 0; side < 2; ++side) {
      set_alternated(sys, o, side == 0);
      Kokkos::fence();
      Kokkos::Timer tb;
      sys.step(o.block);
      Kokkos::fence();
      sec[side] = tb.seconds();
    }
    t_on += sec[0], t_off += sec[1];
    ratio.push_back(sec[1] / sec[0]);
  }
  sys.set_batched_contacts(o.batched);
  sys.set_near_skin(o.near_skin);
  sys.set_near_stream(true);
  sys.set_flag_apart_rows(o.flagged);
  sys.set_packed_stream(o.packed);
  std::cerr << phys << " N " << n << " rep " << r << ": " << o.alternate
            << " on/off rate ratio, median of " << ratio.size() << " block pairs " << median(ratio)
            << ", of the sums " << t_off / t_on << "\n";
  return median(ratio);
}

// Repetition r of a row: a fresh system on the packing, its timed window and, for the first
// repetition, the initial state, the profile and the peak memory.
template <class Model>
void run_repetition(const BenchOptions& o, const std::string& phys, const Model& model, int r,
                    Packing& p, int n, RowMeasures& rm) {
  DemParams prm = dem_params(o, phys);
  if (r == 0 && o.track_memory) perf::AllocationTracker::start();
  Particles<Exec> particles = Particles<Exec>::from_host(p.host);
  // The last system no longer needs the file's copy: peak memory is the engine's.
  if (r == o.reps - 1) p.host = HostParticles();
  DemSystem<Exec, Model> sys(std::move(particles), p.box, model, prm);
  if (o.walls) close_z_faces(sys, p.box);
  if (r == 0) {
    const Measurements mi = sys.measure();
    rm.z_initial = mi.z, rm.ekin_initial = mi.ekin - mi.ekin_rot;
  }
  timed_window(sys, o, n, rm);
  if (!o.alternate.empty()) rm.alternated.push_back(alternate_blocks(sys, o, phys, n, r));
  if (r == 0) {  // one extra profiled window, not part of the timed figures
    sys.set_profile(&rm.prof);
    sys.step(std::min(o.steps, 500L));
    sys.set_profile(nullptr);
  }
  if (r == 0 && o.track_memory) {
    perf::AllocationTracker::stop();
    rm.peak_memory = perf::AllocationTracker::peak_bytes();
    rm.memory_at_peak = perf::AllocationTracker::breakdown_at_peak();
  }
  std::cerr << phys << " N " << n << " rep " << r << ": " << rm.rates.back() / 1e6
            << " M particle-steps/s\n";
}

// The quantities the byte counts are made of. Per particle: nb full-list entries, nb/2 of them
// owned, z_end/2 owned contacts; H history doubles per contact, R 1 for laws with rotations.
struct StepShape {
  double H = 0, R = 0, nb = 0, owned = 0, contacts = 0;
  double body_i = 0, body_j_rest = 0;
};

template <class Model>
StepShape step_shape(const RowMeasures& rm, int n) {
  constexpr double H = Model::history, R = Model::rotations ? 1.0 : 0.0;
  StepShape s;
  s.H = H, s.R = R;
  s.nb = rm.entries / n, s.owned = s.nb / 2, s.contacts = rm.z_end / 2;
  s.body_i = 24 + 24 + 24 * R + 8 + 8 + 4;  // x, v, w, radius, mass, species
  s.body_j_rest = 24 + 24 * R + 8 + 4;      // v, w, mass, species of a partner
  return s;
}

// Damping pass: v, w read, f, torque written. Slab pass: i's state, its list row
// (offsets, owned end, first history row, cell order), per owned entry the partner's x
// and radius and the history (read for the stale check), per contact the partner's
// other fields, the history written and the partner's f and torque read and written;
// then i's f and torque read and written.
double slab_force_bytes(const StepShape& s) {
  const double H = s.H, R = s.R, owned = s.owned, contacts = s.contacts;
  return (24 + 24 * R) * 2 + s.body_i + 16 + owned * (4 + 24 + 8 + 8 * H) +
         contacts * (s.body_j_rest + 8 * H + 48 * (1 + R)) + 48 * (1 + R);
}

// Contacts pass, per owned entry (one row per contact): the list entry, the
// partner's x and radius, the history and the per-contact force row (3 or 9 doubles)
// written, zeros included; per contact the partner's other fields and the history
// written; with a thread per contact, each also reads its row's owner. Gather pass: the
// owned rows read, per other entry the partner's row index and the row, then v, w read
// and f, torque written. Flagged rows: each entry's row becomes its byte, and only
// the touching contacts' rows are written and read (z_end/2 per particle on each
// side of a contact). Mixed precision: positions are read as 12 bytes of integers (the owner's
// and each owned entry's partner's), written by a pass that reads the 24 of the doubles.
double contacts_pass_force_bytes(const StepShape& s, bool flags, bool per_particle, bool mixed) {
  const double H = s.H, R = s.R, nb = s.nb, owned = s.owned, contacts = s.contacts;
  const double row = 8 * (3 + 6 * R);
  // (The owner's state and offsets, read again by each of its contacts' threads,
  // come from cache: counted once, as for a thread per particle.)
  const double owner = s.body_i + 8 + (per_particle ? 0.0 : owned * 4);
  const double entry_row = flags ? 1.0 : row;  // per entry, touching or not
  const double touch_row = flags ? row : 0.0;  // per touching contact, each side
  const double pos = mixed ? 12 : 24;          // bytes of one position as the pass reads it
  const double fixed_update = mixed ? 24 + 12 : 0;
  return owner - (24 - pos) + owned * (4 + pos + 8 + 8 * H + entry_row) +
         contacts * (s.body_j_rest + 8 * H + touch_row) + (24 + 24 * R) + 16 + owned * entry_row +
         (nb - owned) * (4 + entry_row) + 2 * contacts * touch_row + 24 * (1 + R) + fixed_update;
}

// Fused kick-drift (x, v, f, w, torque, mass, inertia, reference x read; x, v, w
// written): the closing kick of each step is deferred into the next one.
// With the packed records (kernels/cpu/particle_pack.hpp), the pass also reads the radius
// and writes a 96-byte record, and the force pass reads the record's 96 bytes where
// it read the 80 of position, radius, velocity and spin.
double integrate_bytes(const StepShape& s, long packed_reads) {
  const double R = s.R;
  const double pack_bytes = packed_reads > 0 ? (8 + 96) + (96 - 80) : 0.0;
  return (24 + 24 + 24 + 24 * R + 24 * R + 8 + 8 * R + 24) + (24 + 24 + 24 * R) + pack_bytes;
}

// The byte counts of a row's step.
struct Traffic {
  double nb = 0;       // full-list entries per particle
  bool flags = false;  // whether the system flagged apart rows
  double bytes = 0;    // the engine's count
  double min_bytes = 0;
  Json terms = Json::object();  // min_bytes term by term
};

// Bytes a particle-step touches, counted from the data the kernels read and write
// (each access once; neighbour data that hits cache still counts), and the least it must move.
template <class Model>
Traffic traffic_model(const BenchOptions& o, const RowMeasures& rm, int n) {
  const StepShape s = step_shape<Model>(rm, n);
  const double H = s.H, R = s.R, owned = s.owned, contacts = s.contacts;
  Traffic t;
  t.nb = s.nb;
  // DemSystem flags apart rows only for laws with rotations (DemParams::flag_apart_rows).
  t.flags = o.flagged && Model::rotations;
  const double force_bytes = o.rows_kernel()
                                 ? contacts_pass_force_bytes(s, t.flags, o.per_particle, o.mixed)
                                 : slab_force_bytes(s);
  t.bytes = force_bytes + integrate_bytes(s, rm.packed_reads);
  // The least a step must move (docs/gpu_memory.md): each particle's state read once
  // and written once (mass and inertia follow from the radius), force and torque
  // written and read once, each contact's history read and written once, the owned
  // list entries' indices read once; partners' data from cache.
  const std::vector<std::pair<const char*, double>> terms{
      {"state_read", 24 + 24 + 8 + 24 * R},
      {"state_written", 24 + 24 + 24 * R},
      {"force_and_torque_written_and_read", 2 * (24 + 24 * R)},
      {"contact_history_read_and_written", contacts * 2 * 8 * H},
      {"owned_neighbour_indices", owned * 4}};
  for (const auto& [term, b] : terms) t.terms[term] = b, t.min_bytes += b;
  return t;
}

// One row: the physics, the packing, what its repetitions measured and the byte counts.
struct RowResult {
  std::string phys, source;
  int n = 0;
  RowMeasures m;
  Traffic t;
  double med = 0;  // median rate, particle-steps per second
};

// The row's law, packing, and the state around the timed window.
void add_state_fields(Json& row, const BenchOptions& o, const BenchContext& c, const RowResult& r) {
  const RowMeasures& m = r.m;
  row["physics"] = r.phys;
  if (r.phys == "hertz_tsuji") row["law_as_lammps_pair_coeff"] = kHertzTsujiCoeff;
  row["N"] = r.n;
  row["source"] = r.source;
  row["walls"] = o.walls ? "z" : "none";
  row["threads"] = c.threads;
  row["phi"] = m.phi;
  row["z_initial"] = m.z_initial;
  row["ekin_translational_initial_J"] = m.ekin_initial * 1e-3;
  row["z_start"] = m.z_start;
  row["z_end"] = m.z_end;
  // Energy unit ug mm^2 / us^2 = 1e-3 J. Translational part separately: that is what
  // LAMMPS reports as `ke`.
  row["ekin_after_warmup_J"] = m.ekin_start * 1e-3;
  row["ekin_after_timed_run_J"] = m.ekin_end * 1e-3;
  row["ekin_translational_after_warmup_J"] = (m.ekin_start - m.erot_start) * 1e-3;
  row["ekin_translational_after_timed_run_J"] = (m.ekin_end - m.erot_end) * 1e-3;
}

// The timed window's counters and rates, and the --alternate ratios.
void add_step_fields(Json& row, const BenchOptions& o, const RowResult& r) {
  const RowMeasures& m = r.m;
  row["neighbors_per_particle_full_list"] = r.t.nb;
  row["neighbor_builds_in_timed_window"] = m.builds;
  row["near_list_recordings_in_timed_window"] = m.near_recordings;
  row["near_list_reads_in_timed_window"] = m.near_reads;
  row["packed_record_reads_in_timed_window"] = m.packed_reads;
  row["precision"] = o.mixed ? "mixed (fixed-point positions)" : "double";
  row["force_kernel"] = o.rows_kernel() ? "two-pass" : "one-pass slabs";
  if (!o.rows_kernel())
    row["force_slabs"] = m.slabs_used;
  else
    row["flag_apart_rows"] = r.t.flags;
  row["particle_steps_per_s"] = m.rates;
  row["median_particle_steps_per_s"] = r.med;
  if (!m.alternated.empty()) {
    row["alternated"] = o.alternate;
    row["alternated_block_steps"] = o.block;
    if (o.alternate == "skin")
      row["alternated_near_skins_a_b"] = std::vector<double>{o.near_skin, o.skin_b};
    row["alternated_on_off_rate_ratio_per_rep"] = m.alternated;
  }
}

// The byte counts, and the bandwidth they make at the median rate.
void add_traffic_fields(Json& row, const BenchOptions& o, const BenchContext& c,
                        const RowResult& r) {
  const double med = r.med, bytes = r.t.bytes, min_bytes = r.t.min_bytes;
  row["bytes_per_particle_step"] = bytes;
  row["achieved_bandwidth_GBs"] = med * bytes / 1e9;
  if (o.triad) row["fraction_of_triad_bandwidth"] = med * bytes / c.bandwidth;
  if (o.triad) row["fraction_of_copy_bandwidth"] = med * bytes / c.copy_bw;
  row["min_traffic_bytes_per_particle_step"] = min_bytes;
  row["min_traffic_terms"] = r.t.terms;
  if (o.triad) row["min_traffic_fraction_of_copy_bandwidth"] = med * min_bytes / c.copy_bw;
}

// Device memory at the peak of the first repetition, array by array.
void add_memory_fields(Json& row, const RowResult& r) {
  const int n = r.n;
  row["peak_device_bytes"] = r.m.peak_memory;
  row["peak_device_bytes_per_particle"] = r.m.peak_memory / n;
  Json arrays = Json::array();
  for (const auto& e : r.m.memory_at_peak) {
    Json a = Json::object();
    a["space"] = e.space;
    a["label"] = e.label;
    a["bytes_per_particle"] = e.bytes / n;
    arrays.push(a);
  }
  row["peak_device_arrays"] = arrays;
}

// The profiled window's time, phase by phase, as fractions of its total.
Json profile_fraction(const StepProfile& prof) {
  const double prof_total = prof.integrate + prof.strain + prof.neighbor + prof.force;
  Json split = Json::object();
  split["force"] = prof.force / prof_total;
  split["integrate"] = prof.integrate / prof_total;
  split["neighbor"] = prof.neighbor / prof_total;
  split["strain"] = prof.strain / prof_total;
  return split;
}

// The row's entry in the result.
Json row_json(const BenchOptions& o, const BenchContext& c, const RowResult& r) {
  Json row = Json::object();
  add_state_fields(row, o, c, r);
  add_step_fields(row, o, r);
  add_traffic_fields(row, o, c, r);
  if (o.track_memory) add_memory_fields(row, r);
  // Peak resident memory of the process so far (all rows up to this one).
  row["resident_kB"] = perf::peak_resident_kB();
  row["profile_fraction"] = profile_fraction(r.m.prof);
  return row;
}

// The row's line on stdout.
void print_row(const BenchOptions& o, const BenchContext& c, const RowResult& r) {
  const double med = r.med, bytes = r.t.bytes;
  std::cout << r.phys << " N " << r.n << " threads " << c.threads << ": median " << med / 1e6
            << " M particle-steps/s, z " << r.m.z_end << ", " << bytes
            << " B/particle-step (minimal " << r.t.min_bytes << ")";
  if (o.track_memory) std::cout << ", peak memory " << r.m.peak_memory / r.n << " B/particle";
  if (o.triad)
    std::cout << ", " << 100 * med * bytes / c.bandwidth << " % of triad " << c.bandwidth / 1e9
              << " GB/s, " << 100 * med * bytes / c.copy_bw << " % of copy " << c.copy_bw / 1e9
              << " GB/s";
  std::cout << "\n";
}

// One row: the packing for n_req (or --data) under one physics, its repetitions, appended to
// `rows` and printed.
template <class Model>
void run_row(const BenchOptions& o, const BenchContext& c, const std::string& phys, int n_req,
             const Model& model, Json& rows) {
  Packing p = load_packing(o, n_req);
  RowResult r;
  r.phys = phys, r.source = p.source;
  r.n = p.host.size();
  for (int rep = 0; rep < o.reps; ++rep) run_repetition(o, phys, model, rep, p, r.n, r.m);
  r.t = traffic_model<Model>(o, r.m, r.n);
  r.med = median(r.m.rates);
  rows.push(row_json(o, c, r));
  print_row(o, c, r);
}

}  // namespace

int main(int argc, char** argv) {
  Kokkos::initialize(argc, argv);
  {
    BenchOptions o;
    const std::string error = parse_options(argc, argv, o);
    if (!error.empty()) {
      std::cerr << error << "\n";
      return 2;
    }
    BenchContext c;
    c.threads = Exec::concurrency();
    if (o.out.empty())
      o.out = "perf/results/dem_throughput_" + std::to_string(c.threads) + "t.json";

    c.bandwidth = o.triad ? perf::triad_bandwidth() : 0.0;
    c.copy_bw = o.triad ? perf::copy_bandwidth() : 0.0;
    Json result = result_header(o, c);
    Json rows = Json::array();

    const std::vector<int> ns = o.data.empty() ? parse_sizes(o.sizes) : std::vector<int>{0};
    const std::vector<std::string> physics_list = physics_names(o.physics);
    for (const std::string& phys : physics_list)
      for (int n_req : ns) {
        auto run_model = [&](const auto& model) { run_row(o, c, phys, n_req, model, rows); };
        if (phys == "hertz_tsuji")
          run_model(hertz_tsuji_model());
        else
          with_contact_model(physics_config(phys), run_model);
      }
    result["rows"] = rows;
    std::filesystem::create_directories(std::filesystem::path(o.out).parent_path());
    write_text_file(o.out, result.dump());
    std::cout << "wrote " << o.out << "\n";
  }
  Kokkos::finalize();
  return 0;
}
