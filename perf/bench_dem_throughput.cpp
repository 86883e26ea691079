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
//                        [--tile NX,NY,NZ] [--no-memory] [--walls]
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

}  // namespace

int main(int argc, char** argv) {
  Kokkos::initialize(argc, argv);
  {
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
    bool track_memory = true, walls = false;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw std::runtime_error("missing value after " + a);
        return argv[++i];
      };
      if (a == "--sizes")
        sizes = next();
      else if (a == "--reps")
        reps = std::stoi(next());
      else if (a == "--steps")
        steps = std::stol(next());
      else if (a == "--warmup")
        warmup = std::stol(next());
      else if (a == "--data")
        data = next();
      else if (a == "--physics")
        physics = next();
      else if (a == "--out")
        out = next();
      else if (a == "--cache")
        cache_dir = next();
      else if (a == "--no-triad")
        triad = false;
      else if (a == "--no-batch")
        batched = false;
      else if (a == "--alternate")
        alternate = next();
      else if (a == "--near-skin")
        near_skin = std::stod(next());
      else if (a == "--skin-b")
        skin_b = std::stod(next());
      else if (a == "--block")
        block = std::stol(next());
      else if (a == "--no-pack")
        packed = false;
      else if (a == "--pack-min")
        pack_min = std::stoi(next());
      else if (a == "--zero-rows")
        flagged = false;
      else if (a == "--thread-per-particle")
        per_particle = true;
      else if (a == "--slabs")
        slabs = std::stoi(next());
      else if (a == "--tile")
        tile = parse_sizes(next());
      else if (a == "--no-memory")
        track_memory = false;
      else if (a == "--walls")
        walls = true;
      else if (a == "--block-rows")
        block_rows = std::stoi(next());
      else if (a.rfind("--kokkos", 0) != 0) {
        std::cerr << "unknown option " << a << "\n";
        return 2;
      }
    }
    if (tile.size() != 3 || *std::min_element(tile.begin(), tile.end()) < 1) {
      std::cerr << "--tile takes three positive counts, NX,NY,NZ\n";
      return 2;
    }
    if (data.empty() && tile != std::vector<int>{1, 1, 1}) {
      std::cerr << "--tile replicates the --data packing; give --data\n";
      return 2;
    }
    if (!alternate.empty() && alternate != "batch" && alternate != "near" &&
        alternate != "stream" && alternate != "skin" && alternate != "rows" &&
        alternate != "pack") {
      std::cerr << "--alternate takes batch, near, stream, skin, rows or pack, not " << alternate
                << "\n";
      return 2;
    }
    if (block < 1) {
      std::cerr << "--block must be at least 1\n";
      return 2;
    }
    const int threads = Exec::concurrency();
    if (out.empty()) out = "perf/results/dem_throughput_" + std::to_string(threads) + "t.json";

    const double bandwidth = triad ? perf::triad_bandwidth() : 0.0;
    const double copy_bw = triad ? perf::copy_bandwidth() : 0.0;
    Json result = Json::object();
    result["benchmark"] = "dem_throughput";
    result["machine"] = perf::machine_info();
    if (triad) result["triad_bandwidth_GBs"] = bandwidth / 1e9;
    if (triad) result["copy_bandwidth_GBs"] = copy_bw / 1e9;
    result["parameters"] =
        "k_n 1e5, gamma_n 1000, k_t 8e4, gamma_t 500, mu 0.5 (mm, us, ug); dt 0.0045, skin 0.2";
    result["steps_timed"] = steps;
    result["warmup_steps"] = warmup;
    result["batched_contacts"] = batched && cpu_has_avx();
    result["near_skin"] = near_skin;
    result["packed_stream"] = packed;
    result["packed_stream_min_particles"] = pack_min;
    result["force_slabs"] = slabs == 0 ? Json("automatic") : Json(slabs);
    result["cell_block_rows"] = block_rows;
    if (!forces_by_slabs<Exec>())
      result["contacts_pass"] = per_particle ? "thread per particle" : "thread per contact";
    Json rows = Json::array();

    const std::vector<int> ns = data.empty() ? parse_sizes(sizes) : std::vector<int>{0};
    std::vector<std::string> physics_list;
    {
      std::stringstream ss(
          physics == "all" ? "frictionless,friction,rolling,hertz_mindlin,hertz_tsuji,hysteretic"
                           : physics);
      std::string item;
      while (std::getline(ss, item, ',')) physics_list.push_back(item);
    }
    for (const std::string& phys : physics_list)
      for (int n_req : ns) {
        auto run_model = [&](const auto& model) {
          using Model = std::decay_t<decltype(model)>;
          PeriodicBox box;
          HostParticles host;
          std::string source;
          if (!data.empty()) {
            LammpsData d = read_lammps_data(data);
            if (d.triclinic())
              throw InputError(data + ": triclinic box (xy xz yz); the DEM box is cuboid");
            host = std::move(d.particles);
            for (int k = 0; k < 3; ++k) box.lo[k] = d.lo[k], box.len[k] = d.len[k];
            source = data;
            if (tile != std::vector<int>{1, 1, 1}) {
              host = tiled(host, box, tile);
              source += " tiled " + std::to_string(tile[0]) + "x" + std::to_string(tile[1]) + "x" +
                        std::to_string(tile[2]);
            }
          } else {
            host = dense_packing(n_req, box, cache_dir);
            source = "generated (seed 12345)";
          }
          if (walls) {
            if (tile[2] != 1) throw InputError("--walls: the packing is not tiled along z");
            box.periodic[2] = false;
            source += ", z faces closed by walls";
          }
          const int n = host.size();
          std::vector<double> rates, alternated;
          StepProfile prof;
          double peak_memory = 0;
          std::vector<perf::AllocationTracker::Entry> memory_at_peak;
          double z_initial = 0, ekin_initial = 0, z_start = 0, z_end = 0, phi = 0, ekin_start = 0,
                 ekin_end = 0, erot_start = 0, erot_end = 0;
          long builds = 0, near_recordings = 0, near_reads = 0, packed_reads = 0;
          int slabs_used = 0;
          double entries = 0;
          for (int r = 0; r < reps; ++r) {
            DemParams prm = bench_params();
            prm.batched_contacts = batched;
            prm.near_skin = near_skin;
            prm.contact_thread_per_particle = per_particle;
            prm.flag_apart_rows = flagged;
            prm.packed_stream = packed;
            prm.packed_stream_min_particles = pack_min;
            prm.force_slabs = slabs, prm.cell_block_rows = block_rows;
            // The time-step guard takes a Hertz contact's stiffness at the largest overlap the
            // run allows: at the benchmark's bound (a whole radius) the deck's dt would be
            // refused. A fifth of the smallest radius is forty times the packing's overlaps.
            if (phys == "hertz_tsuji") prm.max_overlap = 0.2;
            if (r == 0 && track_memory) perf::AllocationTracker::start();
            Particles<Exec> particles = Particles<Exec>::from_host(host);
            // The last system no longer needs the file's copy: peak memory is the engine's.
            if (r == reps - 1) host = HostParticles();
            DemSystem<Exec, Model> sys(std::move(particles), box, model, prm);
            if (walls) {  // the floor and the ceiling, outward normals, the pairs' material
              WallSpec lo, hi;
              lo.name = "floor", hi.name = "ceiling";
              lo.normal[2] = -1.0, hi.normal[2] = 1.0;
              lo.point[2] = box.lo[2], hi.point[2] = box.lo[2] + box.len[2];
              sys.set_walls({lo, hi});
            }
            if (r == 0) {
              const Measurements mi = sys.measure();
              z_initial = mi.z, ekin_initial = mi.ekin - mi.ekin_rot;
            }
            sys.step(warmup);
            const Measurements m0 = sys.measure();
            const long builds0 = sys.neighbor_list().builds();
            const NearListUse near0 = sys.near_list_use();
            Kokkos::fence();
            Kokkos::Timer t;
            sys.step(steps);
            Kokkos::fence();
            const double sec = t.seconds();
            rates.push_back(static_cast<double>(n) * steps / sec);
            const Measurements m1 = sys.measure();
            z_start = m0.z, z_end = m1.z, phi = m1.phi;
            ekin_start = m0.ekin, ekin_end = m1.ekin, erot_start = m0.ekin_rot,
            erot_end = m1.ekin_rot;
            builds = sys.neighbor_list().builds() - builds0;
            near_recordings = sys.near_list_use().recordings - near0.recordings;
            near_reads = sys.near_list_use().reads - near0.reads;
            packed_reads = sys.near_list_use().packed_reads - near0.packed_reads;
            entries = sys.neighbor_list().num_entries();
            slabs_used = sys.neighbor_list().num_slabs();
            if (!alternate.empty()) {  // switched on (A) and off (B) in turn, same trajectory
              std::vector<double> ratio;
              double t_on = 0, t_off = 0;
              for (long s = 0; s + 2 * block <= steps; s += 2 * block) {
                double sec[2];
                for (int side = 0; side < 2; ++side) {
                  const bool on = side == 0;
                  if (alternate == "batch")
                    sys.set_batched_contacts(on);
                  else if (alternate == "stream")
                    sys.set_near_stream(on);
                  else if (alternate == "skin")
                    sys.set_near_skin(on ? near_skin : skin_b);
                  else if (alternate == "rows")
                    sys.set_flag_apart_rows(on);
                  else if (alternate == "pack")
                    sys.set_packed_stream(on);
                  else
                    sys.set_near_skin(on ? near_skin : 0.0);
                  Kokkos::fence();
                  Kokkos::Timer tb;
                  sys.step(block);
                  Kokkos::fence();
                  sec[side] = tb.seconds();
                }
                t_on += sec[0], t_off += sec[1];
                ratio.push_back(sec[1] / sec[0]);
              }
              sys.set_batched_contacts(batched);
              sys.set_near_skin(near_skin);
              sys.set_near_stream(true);
              sys.set_flag_apart_rows(flagged);
              sys.set_packed_stream(packed);
              std::cerr << phys << " N " << n << " rep " << r << ": " << alternate
                        << " on/off rate ratio, median of " << ratio.size() << " block pairs "
                        << median(ratio) << ", of the sums " << t_off / t_on << "\n";
              alternated.push_back(median(ratio));
            }
            if (r == 0) {  // one extra profiled window, not part of the timed figures
              sys.set_profile(&prof);
              sys.step(std::min(steps, 500L));
              sys.set_profile(nullptr);
            }
            if (r == 0 && track_memory) {
              perf::AllocationTracker::stop();
              peak_memory = perf::AllocationTracker::peak_bytes();
              memory_at_peak = perf::AllocationTracker::breakdown_at_peak();
            }
            std::cerr << phys << " N " << n << " rep " << r << ": " << rates.back() / 1e6
                      << " M particle-steps/s\n";
          }
          // Bytes a particle-step touches, counted from the data the kernels read and write
          // (each access once; neighbour data that hits cache still counts). Per particle:
          // nb full-list entries, nb/2 of them owned, z_end/2 owned contacts.
          constexpr double H = Model::history, R = Model::rotations ? 1.0 : 0.0;
          // DemSystem flags apart rows only for laws with rotations (DemParams::flag_apart_rows).
          const bool flags = flagged && Model::rotations;
          const double nb = entries / n, owned = nb / 2, contacts = z_end / 2;
          const double body_i = 24 + 24 + 24 * R + 8 + 8 + 4;  // x, v, w, radius, mass, species
          const double body_j_rest = 24 + 24 * R + 8 + 4;      // v, w, mass, species of a partner
          double force_bytes = 0;
          if (forces_by_slabs<Exec>()) {
            // Damping pass: v, w read, f, torque written. Slab pass: i's state, its list row
            // (offsets, owned end, first history row, cell order), per owned entry the partner's x
            // and radius and the history (read for the stale check), per contact the partner's
            // other fields, the history written and the partner's f and torque read and written;
            // then i's f and torque read and written.
            force_bytes = (24 + 24 * R) * 2 + body_i + 16 + owned * (4 + 24 + 8 + 8 * H) +
                          contacts * (body_j_rest + 8 * H + 48 * (1 + R)) + 48 * (1 + R);
          } else {
            // Contacts pass, per owned entry (one row per contact): the list entry, the
            // partner's x and radius, the history and the per-contact force row (3 or 9 doubles)
            // written, zeros included; per contact the partner's other fields and the history
            // written; with a thread per contact, each also reads its row's owner. Gather pass: the
            // owned rows read, per other entry the partner's row index and the row, then v, w read
            // and f, torque written. Flagged rows: each entry's row becomes its byte, and only
            // the touching contacts' rows are written and read (z_end/2 per particle on each
            // side of a contact).
            const double row = 8 * (3 + 6 * R);
            // (The owner's state and offsets, read again by each of its contacts' threads,
            // come from cache: counted once, as for a thread per particle.)
            const double owner = body_i + 8 + (per_particle ? 0.0 : owned * 4);
            const double entry_row = flags ? 1.0 : row;  // per entry, touching or not
            const double touch_row = flags ? row : 0.0;  // per touching contact, each side
            force_bytes = owner + owned * (4 + 24 + 8 + 8 * H + entry_row) +
                          contacts * (body_j_rest + 8 * H + touch_row) + (24 + 24 * R) + 16 +
                          owned * entry_row + (nb - owned) * (4 + entry_row) +
                          2 * contacts * touch_row + 24 * (1 + R);
          }
          // Fused kick-drift (x, v, f, w, torque, mass, inertia, reference x read; x, v, w
          // written): the closing kick of each step is deferred into the next one.
          // With the packed records (kernels/cpu/particle_pack.hpp), the pass also reads the radius
          // and writes a 96-byte record, and the force pass reads the record's 96 bytes where
          // it read the 80 of position, radius, velocity and spin.
          const double pack_bytes = packed_reads > 0 ? (8 + 96) + (96 - 80) : 0.0;
          const double integrate_bytes =
              (24 + 24 + 24 + 24 * R + 24 * R + 8 + 8 * R + 24) + (24 + 24 + 24 * R) + pack_bytes;
          const double bytes = force_bytes + integrate_bytes;
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
          Json traffic = Json::object();
          double min_bytes = 0;
          for (const auto& [term, b] : terms) traffic[term] = b, min_bytes += b;
          const double med = median(rates);
          const double prof_total = prof.integrate + prof.strain + prof.neighbor + prof.force;
          Json row = Json::object();
          row["physics"] = phys;
          if (phys == "hertz_tsuji") row["law_as_lammps_pair_coeff"] = kHertzTsujiCoeff;
          row["N"] = n;
          row["source"] = source;
          row["walls"] = walls ? "z" : "none";
          row["threads"] = threads;
          row["phi"] = phi;
          row["z_initial"] = z_initial;
          row["ekin_translational_initial_J"] = ekin_initial * 1e-3;
          row["z_start"] = z_start;
          row["z_end"] = z_end;
          // Energy unit ug mm^2 / us^2 = 1e-3 J. Translational part separately: that is what
          // LAMMPS reports as `ke`.
          row["ekin_after_warmup_J"] = ekin_start * 1e-3;
          row["ekin_after_timed_run_J"] = ekin_end * 1e-3;
          row["ekin_translational_after_warmup_J"] = (ekin_start - erot_start) * 1e-3;
          row["ekin_translational_after_timed_run_J"] = (ekin_end - erot_end) * 1e-3;
          row["neighbors_per_particle_full_list"] = nb;
          row["neighbor_builds_in_timed_window"] = builds;
          row["near_list_recordings_in_timed_window"] = near_recordings;
          row["near_list_reads_in_timed_window"] = near_reads;
          row["packed_record_reads_in_timed_window"] = packed_reads;
          if (forces_by_slabs<Exec>())
            row["force_slabs"] = slabs_used;
          else
            row["flag_apart_rows"] = flags;
          row["particle_steps_per_s"] = rates;
          row["median_particle_steps_per_s"] = med;
          if (!alternated.empty()) {
            row["alternated"] = alternate;
            row["alternated_block_steps"] = block;
            if (alternate == "skin")
              row["alternated_near_skins_a_b"] = std::vector<double>{near_skin, skin_b};
            row["alternated_on_off_rate_ratio_per_rep"] = alternated;
          }
          row["bytes_per_particle_step"] = bytes;
          row["achieved_bandwidth_GBs"] = med * bytes / 1e9;
          if (triad) row["fraction_of_triad_bandwidth"] = med * bytes / bandwidth;
          if (triad) row["fraction_of_copy_bandwidth"] = med * bytes / copy_bw;
          row["min_traffic_bytes_per_particle_step"] = min_bytes;
          row["min_traffic_terms"] = traffic;
          if (triad) row["min_traffic_fraction_of_copy_bandwidth"] = med * min_bytes / copy_bw;
          if (track_memory) {
            // Device memory at the peak of the first repetition, array by array.
            row["peak_device_bytes"] = peak_memory;
            row["peak_device_bytes_per_particle"] = peak_memory / n;
            Json arrays = Json::array();
            for (const auto& e : memory_at_peak) {
              Json a = Json::object();
              a["space"] = e.space;
              a["label"] = e.label;
              a["bytes_per_particle"] = e.bytes / n;
              arrays.push(a);
            }
            row["peak_device_arrays"] = arrays;
          }
          // Peak resident memory of the process so far (all rows up to this one).
          row["resident_kB"] = perf::peak_resident_kB();
          Json split = Json::object();
          split["force"] = prof.force / prof_total;
          split["integrate"] = prof.integrate / prof_total;
          split["neighbor"] = prof.neighbor / prof_total;
          split["strain"] = prof.strain / prof_total;
          row["profile_fraction"] = split;
          rows.push(row);
          std::cout << phys << " N " << n << " threads " << threads << ": median " << med / 1e6
                    << " M particle-steps/s, z " << z_end << ", " << bytes
                    << " B/particle-step (minimal " << min_bytes << ")";
          if (track_memory) std::cout << ", peak memory " << peak_memory / n << " B/particle";
          if (triad)
            std::cout << ", " << 100 * med * bytes / bandwidth << " % of triad " << bandwidth / 1e9
                      << " GB/s, " << 100 * med * bytes / copy_bw << " % of copy " << copy_bw / 1e9
                      << " GB/s";
          std::cout << "\n";
        };
        if (phys == "hertz_tsuji")
          run_model(hertz_tsuji_model());
        else
          with_contact_model(physics_config(phys), run_model);
      }
    result["rows"] = rows;
    std::filesystem::create_directories(std::filesystem::path(out).parent_path());
    write_text_file(out, result.dump());
    std::cout << "wrote " << out << "\n";
  }
  Kokkos::finalize();
  return 0;
}
