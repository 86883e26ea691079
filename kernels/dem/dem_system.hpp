// A DEM system: particles in a periodic (optionally deforming) box, or a box closed by
// walls on some axes, a neighbour list and a contact model (optionally with a multi-contact
// law on top), advanced by velocity Verlet. Owns the physical-safety guards: the time
// step against the shortest collision, NaN, runaway overlap and runaway energy.
#pragma once
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/dem/box.hpp"
#include "core/dem/particles.hpp"
#include "core/dem/walls.hpp"
#include "core/run/error.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/contact_forces.hpp"
#include "kernels/dem/contact_history.hpp"
#include "kernels/dem/integrator.hpp"
#include "kernels/dem/measure.hpp"
#include "kernels/dem/multicontact.hpp"
#include "kernels/dem/neighbor_list.hpp"
#include "kernels/dem/strain.hpp"
#include "kernels/dem/wall_forces.hpp"

namespace granular {

struct DemParams {
  double dt = 0.0;
  double skin = 0.0;
  Damping damping;
  int rattler_threshold = 3;
  double max_overlap = 0.3;       // delta / min(a_i, a_j) above which the run is stopped
  double dt_guard = 0.1;          // dt must not exceed this fraction of the shortest collision
  std::string dt_key = "dt";      // the scene key of dt, named by the guard's advice
  std::string dt_hint;            // or, where dt is derived, what to change instead
  bool sort = true;               // reorder particles in cell order at every rebuild (locality)
  long rebuild_every = 0;         // > 0: rebuild the neighbour list every this many steps, whatever
                                  // the skin criterion says (tests, benchmarks of flowing systems)
  double gravity[3] = {0, 0, 0};  // body force per unit mass
  bool two_pass_forces = false;   // host backends: the device's two-pass force kernel instead of
                                  // the one-pass slab kernel (tests compare the two)
  bool batched_contacts = true;   // host one-pass kernel: laws with a batched (vector)
                                  // evaluation use it; false: contact by contact (tests)
  bool contact_thread_per_particle = false;  // two-pass kernel: one thread per particle over its
                                             // contacts (the earlier mapping, for comparison)
  // Two-pass kernel, laws with rotations (rows of 9 doubles): an apart pair marks a byte
  // instead of writing a zero row, and the gather skips its row (the same bits; the
  // frictionless law's rows of 3 doubles cost about what the byte does).
  bool flag_apart_rows = true;
  int force_slabs = 0;      // host one-pass kernel: slabs along z (0: default_force_slabs(),
                            // six; a third of them run at once, see NeighborList::set_partition)
  int cell_block_rows = 4;  // cell order: height of the blocks of cell rows a slab is swept in
  // Host one-pass kernel: the skin of the near list (NearRows in kernels/dem/contact_forces.hpp),
  // the owned entries within this gap of touching, read instead of the whole rows while no
  // particle has moved half of it (the same bits either way). < 0: a thirty-second of `skin`
  // where the near stream reads it with the frictional law (below), a sixteenth otherwise
  // (docs/perf_design_notes.md, CPUs: thinner gaps record more often, which costs about a pass
  // over the whole rows, and save the apart entries of every other pass; the frictional
  // stream's reads gain from the thinner gap, the rows' and the frictionless stream's do
  // not); 0: no near list.
  // Used in runs of at least kNearMinSteps steps without strain.
  double near_skin = -1.0;
  // Host one-pass kernel, the batched law or the frictionless linear law, with one parameter
  // set: the near list also recorded as a flat stream of contacts and read four at a time
  // (kernels/cpu/near_stream.hpp; the same bits either way).
  bool near_stream = true;
  // The frictional stream reads each particle's position, radius, velocity and spin from one
  // packed record, written by the step's kick-drift pass (kernels/cpu/particle_pack.hpp: two
  // cache lines per partner instead of four, 96 bytes more per particle; the same bits either
  // way), in systems of at least packed_stream_min_particles: it gains 1.18x at N = 262144
  // and costs 0.98x at 4096 and 32768, whose particle arrays the caches hold anyway
  // (docs/perf_design_notes.md, CPUs).
  bool packed_stream = true;
  int packed_stream_min_particles = 65536;
  // Mixed precision (docs/mixed_precision.md): the force pass reads the positions as 32-bit
  // fixed-point fractions of the box (kernels/dem/fixed_point.hpp), refreshed from the double
  // positions before each pass; forces, torques, histories and their sums stay in double, and
  // so do the integration and the measurements. Runs the two-pass kernel on every backend;
  // classical laws only (not with multi-contact laws). Off by default: the results then are
  // those of double precision bit for bit.
  bool mixed_precision = false;
  // What each wall feels, kept as sums by block of particles or as one row per (particle,
  // wall) (kernels/dem/wall_record.hpp: the same bits; rows cost 72 bytes a wall for every
  // particle). Auto: blocks on host backends where every thread has blocks enough; tests
  // compare the two.
  WallLayout wall_layout = WallLayout::Auto;
};

// Wall time per phase of the step, filled only when profiling is switched on (it fences
// after every phase, which a production run should not pay for).
struct StepProfile {
  double integrate = 0, strain = 0, neighbor = 0, force = 0;
  long rebuilds = 0;
};

// How often the force passes recorded the near list and read it (NearRows; runs of step()
// long enough for it).
struct NearListUse {
  long recordings = 0, reads = 0;
  long stream_reads = 0;  // reads served by the near list's stream (kernels/cpu/near_stream.hpp)
  long packed_reads = 0;  // those of them from the particles' packed records (ParticlePack)
};

template <class ExecSpace, class Model>
class DemSystem {
 public:
  using execution_space = ExecSpace;
  using model_type = Model;
  using particles_type = Particles<ExecSpace>;

  DemSystem(Particles<ExecSpace> particles, const PeriodicBox& box, const Model& model,
            const DemParams& params)
      : p_(std::move(particles)), box_(box), model_(model), params_(params), nl_(params.skin) {
    particle_volume_ = set_up();
    check_time_step();
    wrap_positions(p_, box_);  // inputs (data files) may hold positions outside the box
    rebuild();
    forces(0.0);  // initial forces: no spring increment for a step not taken
  }

  // A system that continues the saved one `s` (saved(), or read_restart of
  // scenarios/common/restart_file.hpp) bitwise, made from it alone: without the neighbour
  // build and force pass a fresh system makes, whose results restore() would replace (the
  // saved list, histories, forces and clock are the state). `origin` names the state in the
  // errors. A saved state with walls is refused here: make that system fresh, set its walls,
  // then restore().
  struct Saved;
  DemSystem(const Saved& s, const Model& model, const DemParams& params, const std::string& origin)
      : p_(s.particles), box_(s.box), model_(model), params_(params), nl_(params.skin) {
    if (s.wall_history.extent(0) > 0 || s.walls.touch.extent(0) > 0)
      throw InputError(origin + " holds walls: restore it into a system with the same walls");
    set_up();  // the saved state brings its particle volume
    restore(s, origin);
    check_time_step();
  }

  // Move-only: the members are Kokkos Views, which copy as shared references, so a copy
  // would silently step the same particles and histories as the original.
  DemSystem(const DemSystem&) = delete;
  DemSystem& operator=(const DemSystem&) = delete;
  DemSystem(DemSystem&&) = default;
  DemSystem& operator=(DemSystem&&) = default;

  // Advances n steps of velocity Verlet with the current strain rate.
  void step(long n) {
    const double dt = params_.dt;
    const bool straining = rate_[0] != 0.0 || rate_[1] != 0.0 || rate_[2] != 0.0;
    if (profile_) return step_profiled(n);
    // The closing half kick of each step is deferred into the next step's first pass (same
    // arithmetic, one sweep less); the last one is applied before returning.
    const DampingStart damp = damping_start();
    NearTrack near(near_usable(n, straining));
    double* pack = near.on ? packed_records() : nullptr;
    for (long s = 0; s < n; ++s) {
      const double max_sq =
          kick_drift<kRot>(p_, box_, nl_.reference(), dt, s > 0, damp, near.drift_speed(), pack);
      if (straining) apply_affine_strain(p_, nl_.reference(), box_, rate_, dt);
      if (rebuild_due(max_sq)) {
        rebuild();  // permutes f and torque with the particles, releases the packed records
        near.valid = false;
        if (pack) pack = packed_records();
      }
      walls_.update(time_ + dt);
      forces(dt, damp.on, near_mode(near), near.on, pack);
      time_ += dt;
      ++steps_;
    }
    if (n > 0) kick<kRot>(p_, dt);
  }

  // Same step, timed per phase (for benchmarks). Pass nullptr to switch off.
  void set_profile(StepProfile* profile) { profile_ = profile; }

  // Same physics with other parameters (e.g. infinite friction for probing); history kept.
  void set_model(const Model& model) { model_ = model; }

  void set_strain_rate(double ex, double ey, double ez) {
    if (walls_.size() > 0 && (ex != 0.0 || ey != 0.0 || ez != 0.0))
      throw InputError("a box with walls is not strained: move the walls instead");
    rate_[0] = ex, rate_[1] = ey, rate_[2] = ez;
  }

  // Planar walls (closing the non-periodic axes of the box). Contact histories start
  // fresh; forces are recomputed at the current time.
  void set_walls(std::vector<WallSpec> specs) {
    if (rate_[0] != 0.0 || rate_[1] != 0.0 || rate_[2] != 0.0)
      throw InputError("a box with walls is not strained: move the walls instead");
    for (auto& w : specs) w.validate("wall " + w.name);
    walls_ = WallSet<ExecSpace>(std::move(specs));
    walls_.update(time_);
    const int nw = walls_.size();
    constexpr int H = Model::history;
    wall_history_ = wall_view("dem::wall_history", nw > 0 && H > 0 ? p_.n : 0, nw * H);
    wall_record_.reset(p_.n, nw, params_.wall_layout);
    mc_.resize_walls(p_.n, nw);
    external_ = nw > 0;
    for (int d = 0; d < 3; ++d) external_ = external_ || params_.gravity[d] != 0.0;
    check_time_step();
    initial_forces();
  }

  // Multi-contact law on top of the contact model (mode None: the classical kernels, bit
  // for bit). Forces are recomputed at the current state; MC-strain, which uses each
  // contact's normal force of the previous evaluation, is evaluated twice, so that a state
  // already under load starts with its own (classical) forces as the previous ones instead
  // of none.
  void set_multicontact(const MultiContact& mc) {
    bool used[kMaxSpecies] = {};
    auto species = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p_.species);
    for (int i = 0; i < p_.n; ++i) {
      if (species(i) < 0 || species(i) >= kMaxSpecies)
        throw InputError("particle species " + std::to_string(species(i)) + " out of range");
      used[species(i)] = true;
    }
    if (params_.mixed_precision && mc.mode != MultiContact::None)
      throw InputError(
          "mixed precision covers the classical contact laws only: switch it off "
          "(DemParams::mixed_precision) to run a multi-contact law");
    mc.validate(used);
    // Multi-contact laws act between the two passes, which need the per-contact forces.
    size_pair_buffer(two_pass() || mc.mode != MultiContact::None, mc.mode != MultiContact::None);
    mc_.configure(mc, p_, nl_, walls_.size(), pair_.extent(0));
    check_time_step();
    initial_forces();
  }
  const MultiContact& multicontact() const { return mc_.options(); }
  const WallSet<ExecSpace>& walls() const { return walls_; }
  // Force, torque, contacts and energy of each wall, as of the last force evaluation.
  std::vector<WallLoad> wall_loads() const { return wall_record_.loads(); }
  // Per-(particle, wall) history rows (particle order as in memory), for saved states.
  const Kokkos::View<double**, Kokkos::LayoutRight, typename ExecSpace::memory_space>&
  wall_history() const {
    return wall_history_;
  }
  // Forces depend on velocities (damping): recompute after external edits of the state.
  void refresh_forces() { forces(0.0); }
  // Neighbour list from scratch, contact history carried over by partner identity.
  // With sorting, particles are first put in cell order, so that neighbours sit close in
  // memory; every per-particle array is permuted and the history follows by identity.
  void rebuild() {
    // The near list and its stream are recorded again after a rebuild: released first, so
    // that they do not add to the peak of the permutation and the build. So are the packed
    // records: the step's kick-drift pass wrote them in the order the rebuild changes, and
    // the next force pass records the near list instead of reading them; the next kick-drift
    // pass writes them all again (step() asks for them anew, packed_records()). The peak of
    // a rebuild is the contact history's remap, which holds two copies of it.
    near_k_ = int_view();
    near_stream_.release();
    pack_ = pack_view();
    typename Particles<ExecSpace>::int_view order;
    if (params_.sort) {
      nl_.bin(p_, box_);
      order = typename Particles<ExecSpace>::int_view("dem::sort_order", p_.n);
      Kokkos::deep_copy(order, Kokkos::subview(nl_.cell_order(), std::make_pair(0, p_.n)));
      p_.permute(order);
      permute_rows<ExecSpace>(wall_history_, order, p_.n);
      wall_record_.reorder(order, p_.n);
      mc_.reorder(order, p_.n);
    }
    nl_.build(p_, box_, params_.sort);
    history_.remap(p_, nl_, order);
    size_pair_buffer(two_pass(), mc_.active());
    mc_.after_build(p_, nl_, order, pair_.extent(0));
  }

  // Pair measurements; wall contacts add their elastic energy and their overlaps (stress,
  // fabric and coordination stay those of the particle contacts).
  // With a multi-contact law, epot stays the binary contact law's energy at the geometric
  // overlaps (the corrected forces, explicit and many-body, derive from no potential: the
  // figure is the classical reference, not a conserved quantity), and max_overlap stays
  // geometric, which is what the runaway-overlap guard and the lever arms depend on.
  Measurements measure() const {
    Measurements m = granular::measure(p_, nl_, history_view(), box_, model_,
                                       params_.rattler_threshold, particle_volume_);
    if (walls_.size() > 0)
      for (const WallLoad& w : wall_loads()) {
        m.epot += w.energy;
        m.max_overlap = std::max(m.max_overlap, w.max_overlap);
      }
    return m;
  }
  // Per-contact history, one row per contact in its owner's rows (NeighborList::pair_begin;
  // empty for models without).
  typename ContactHistory<ExecSpace, Model::history>::values_view history_view() const {
    if constexpr (Model::history > 0)
      return history_.values();
    else
      return dummy_history_;
  }

  // The first particle (lowest index) whose position, velocity or spin is NaN or inf; n if
  // none. The measurements alone miss it: a NaN distance reads as "apart", so such a
  // particle drops out of every contact, maximum and sum without a trace.
  int first_non_finite_particle() const {
    const auto x = p_.x, v = p_.v, w = p_.w;
    int first = p_.n;
    Kokkos::parallel_reduce(
        "dem::DemSystem::finite_state", Kokkos::RangePolicy<ExecSpace>(0, p_.n),
        KOKKOS_LAMBDA(const int i, int& lowest) {
          double s = 0;  // x - x is 0 for a finite x, NaN for NaN or inf
          for (int d = 0; d < 3; ++d)
            s += (x(i, d) - x(i, d)) + (v(i, d) - v(i, d)) + (w(i, d) - w(i, d));
          if (!(s == 0.0) && i < lowest) lowest = i;
        },
        Kokkos::Min<int>(first));
    return first;
  }

  // Stops the run with a message that says what to change.
  void check_health(const Measurements& m) const {
    std::ostringstream msg;
    msg.precision(4);
    if (const int bad = first_non_finite_particle(); bad < p_.n) {
      msg << "non-finite position, velocity or spin of particle " << bad << " at t = " << time_
          << " (step " << steps_ << "): the integration diverged; reduce dt (now " << params_.dt
          << ")";
      throw PhysicsError(msg.str());
    }
    if (!std::isfinite(m.ekin) || !std::isfinite(m.epot) || !std::isfinite(m.pressure)) {
      msg << "non-finite energy or stress at t = " << time_ << " (step " << steps_
          << "): the integration diverged; reduce dt (now " << params_.dt << ")";
      throw PhysicsError(msg.str());
    }
    // MC-strain: the pair law sees the corrected overlap, and the time-step guard assumed
    // the limit for it as well.
    const double corrected = mc_.max_corrected_overlap(p_, nl_);
    if (m.max_overlap > params_.max_overlap || corrected > params_.max_overlap) {
      msg << "runaway overlap at t = " << time_ << " (step " << steps_
          << "): delta/a = " << std::max(m.max_overlap, corrected)
          << (corrected > m.max_overlap ? " (MC-strain's corrected overlap)" : "")
          << " exceeds the limit " << params_.max_overlap
          << " of binary contact laws; reduce the strain rate, the final volume fraction, the"
          << " initial velocities or dt";
      // MC-strain takes the other contacts' forces of the previous step: under load its
      // feedback gain (growing with the number of contacts and with sqrt(delta/d)) passes 1 and the
      // overlap grows geometrically, whatever dt; only a lighter load or a smaller gamma helps.
      if (mc_.options().mode == MultiContact::Strain)
        msg << "; with MC-strain (gamma = " << mc_.options().gamma
            << ") this is the explicit correction's feedback outgrowing the contact: lower"
            << " the load or gamma, or use MC-stress";
      throw PhysicsError(msg.str());
    }
    // Kinetic energy per particle that could drive an overlap beyond the limit on impact.
    const double delta_ref = params_.max_overlap * a_min_;
    const double e_limit = 0.5 * model_.stiffness(delta_ref, 2 * a_max_) * delta_ref * delta_ref;
    if (p_.n > 0 && m.ekin / p_.n > e_limit) {
      msg << "runaway kinetic energy at t = " << time_ << " (step " << steps_
          << "): " << m.ekin / p_.n << " per particle exceeds " << e_limit
          << ", the energy of a limit overlap; reduce dt, the strain rate or the initial"
          << " velocities, or raise the damping";
      throw PhysicsError(msg.str());
    }
  }

  Particles<ExecSpace>& particles() { return p_; }
  const Particles<ExecSpace>& particles() const { return p_; }
  const PeriodicBox& box() const { return box_; }
  const NeighborList<ExecSpace>& neighbor_list() const { return nl_; }
  const Model& model() const { return model_; }
  const DemParams& params() const { return params_; }
  NearListUse near_list_use() const {
    NearListUse u = near_use_;
    u.stream_reads = near_stream_.reads;
    u.packed_reads = near_stream_.packed_reads;
    return u;
  }
  // The host kernel's contact batch on or off mid-run (the same bits either way): lets a
  // benchmark alternate the two on one trajectory.
  void set_batched_contacts(bool on) { params_.batched_contacts = on; }
  // The near list's skin mid-run (DemParams::near_skin; the same bits for any value).
  void set_near_skin(double skin) { params_.near_skin = skin; }
  // The near list's stream on or off mid-run (DemParams::near_stream; the same bits).
  void set_near_stream(bool on) { params_.near_stream = on; }
  // The stream's packed particle records on or off mid-run (DemParams::packed_stream; the
  // same bits).
  void set_packed_stream(bool on) { params_.packed_stream = on; }
  // The two-pass kernel's flagged apart rows on or off mid-run (DemParams::flag_apart_rows;
  // the same bits).
  void set_flag_apart_rows(bool on) { params_.flag_apart_rows = on; }
  double time() const { return time_; }
  long steps() const { return steps_; }
  void set_clock(double t, long steps) {
    time_ = t, steps_ = steps;
    walls_.update(time_);
  }
  double particle_volume() const { return particle_volume_; }

  // Exact restart: everything the next step reads, as it is now (particles in their current
  // order with forces and torques, the neighbour list and its reference positions, contact
  // and wall histories, box, strain rate, clock), as the system's own Views: saving touches
  // nothing, so a run that writes checkpoints is bitwise the run that does not; restoring
  // into a system made from the same particles, model, parameters and walls continues bitwise
  // where the saved one was. scenarios/common/restart_file.hpp writes and reads it.
  using history_type = ContactHistory<ExecSpace, Model::history, true>;
  using wall_view = Kokkos::View<double**, Kokkos::LayoutRight, typename ExecSpace::memory_space>;
  struct Saved {
    Particles<ExecSpace> particles;
    typename NeighborList<ExecSpace>::Saved list;
    typename history_type::Saved history;
    wall_view wall_history;
    typename WallRecord<ExecSpace>::Saved walls;  // what the walls felt, and which contacts stood
    double time = 0.0;
    long steps = 0;
    double particle_volume = 0.0;
    PeriodicBox box;
    double rate[3] = {0, 0, 0};
  };
  Saved saved() const {
    if (mc_.active())
      throw InputError(
          "exact restarts of multi-contact runs are not supported: their "
          "previous-step contact forces are not saved");
    Saved s;
    s.particles = p_, s.list = nl_.saved(), s.history = history_.saved();
    s.wall_history = wall_history_, s.walls = wall_record_.saved();
    s.time = time_, s.steps = steps_, s.particle_volume = particle_volume_, s.box = box_;
    for (int d = 0; d < 3; ++d) s.rate[d] = rate_[d];
    return s;
  }
  // `origin` names where the state came from in the errors.
  void restore(const Saved& s, const std::string& origin) {
    const Particles<ExecSpace>& q = s.particles;
    if (q.n != p_.n) throw InputError(origin + " holds another number of particles");
    // Spelt out, not a braced list: nvcc's front end rejects some of those here.
    const auto rows = static_cast<size_t>(q.n);
    const bool lengths = q.x.extent(0) == rows && q.v.extent(0) == rows && q.w.extent(0) == rows &&
                         q.f.extent(0) == rows && q.torque.extent(0) == rows &&
                         q.radius.extent(0) == rows && q.mass.extent(0) == rows &&
                         q.inertia.extent(0) == rows && q.species.extent(0) == rows &&
                         q.id.extent(0) == rows;
    if (!lengths) throw InputError(origin + " holds particle arrays of different lengths");
    auto same_shape = [](const wall_view& a, const wall_view& b) {
      return a.extent(0) == b.extent(0) && a.extent(1) == b.extent(1);
    };
    if (!same_shape(s.wall_history, wall_history_) || !wall_record_.same_shape(s.walls))
      throw InputError(origin + " holds the walls of another system");
    p_ = q;
    nl_.restore(s.list, origin + "/neighbor_list");
    history_.restore(s.history, nl_, origin + "/history");
    wall_history_ = s.wall_history;
    wall_record_.restore(s.walls);
    time_ = s.time, steps_ = s.steps, particle_volume_ = s.particle_volume, box_ = s.box;
    for (int d = 0; d < 3; ++d) rate_[d] = s.rate[d];
    walls_.update(time_);
    size_pair_buffer(two_pass(), mc_.active());
  }

 private:
  // What both constructors derive from the particles and the parameters: the radius range
  // the time-step guard reads, whether an external field acts, and the neighbour list's
  // partition. Returns the particles' total volume.
  double set_up() {
    if (!(params_.dt > 0)) throw InputError("time step dt must be positive");
    double volume = 0.0;
    {  // scoped: on a host backend the mirror is the array itself, which the sort replaces
      auto radius = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p_.radius);
      for (int i = 0; i < p_.n; ++i) {
        volume += 4.0 / 3.0 * M_PI * radius(i) * radius(i) * radius(i);
        a_min_ = std::min(a_min_, radius(i));
        a_max_ = std::max(a_max_, radius(i));
      }
    }
    for (int d = 0; d < 3; ++d) external_ = external_ || params_.gravity[d] != 0.0;
    if (params_.mixed_precision) check_fixed_point_box();
    nl_.set_partition(params_.force_slabs, params_.cell_block_rows);
    nl_.keep_mirror(false);  // the indices the first build makes (size_pair_buffer)
    nl_.keep_pair_index(two_pass());
    return volume;
  }
  static constexpr bool kRot = Model::rotations;

  // The fixed-point separation takes the minimum image by integer wrap-around, so a listed
  // pair must be less than half a box length apart in every dimension, walled ones included.
  void check_fixed_point_box() const {
    const double reach = 2 * a_max_ + params_.skin;
    for (int d = 0; d < 3; ++d)
      if (!(box_.len[d] > 2 * reach))
        throw InputError(
            "mixed precision needs every box length above twice the neighbour "
            "reach (2 a_max + skin = " +
            std::to_string(reach) + "); dimension " + std::to_string(d) + " is " +
            std::to_string(box_.len[d]) + ": switch mixed_precision off");
  }

  // The per-contact force array of the two-pass kernel: allocated only where that kernel
  // runs (devices, multi-contact laws, or on request), since it is ~40 % of the memory.
  bool two_pass() const {
    return params_.two_pass_forces || params_.mixed_precision || mc_.active() ||
           !forces_by_slabs<ExecSpace>();
  }
  // Multi-contact laws index it by list entry (both sides of a contact read their entries)
  // through the list's mirror; the classical laws by pair row (half the rows) through the
  // list's pair index. The list keeps only the index the kernel in use reads.
  void size_pair_buffer(bool needed, bool by_entry) {
    nl_.keep_mirror(needed && by_entry);
    nl_.keep_pair_index(needed && !by_entry);
    if (!needed) {
      pair_ = pair_view();
      row_flags_ = RowFlags<ExecSpace>();
      return;
    }
    constexpr int nb = Model::rotations ? 9 : 3;
    const size_t rows = by_entry ? nl_.num_entries() : nl_.num_pairs();
    if (pair_.extent(0) < rows || pair_.extent(0) == 0)
      pair_ = pair_view("dem::pair_forces", rows + rows / 8 + 16, nb);
    if (by_entry || !Model::rotations)
      row_flags_ = RowFlags<ExecSpace>();
    else if (row_flags_.extent(0) != pair_.extent(0))
      row_flags_ = RowFlags<ExecSpace>(
          Kokkos::view_alloc(Kokkos::WithoutInitializing, "dem::pair_row_flags"), pair_.extent(0));
  }

  bool rebuild_due(double max_sq) const {
    if (params_.rebuild_every > 0)
      return steps_ % params_.rebuild_every == params_.rebuild_every - 1;
    return nl_.needs_rebuild(max_sq, box_);
  }
  // The one-pass host kernel's force sums start in the integrator's pass (one sweep over
  // the particles fewer per step); the other force passes set the damping themselves.
  DampingStart damping_start() const {
    DampingStart d;
    d.on = !two_pass();
    d.translational = params_.damping.translational;
    d.rotational = params_.damping.rotational;
    return d;
  }
  // The near list within one call of step(): recorded by the first force pass, read by the
  // next ones while no particle can have moved half the near skin since: each drift moves a
  // particle by dt |v| at most (plus the round-off of its position), so the sum over the
  // steps of dt times the largest speed (kick_drift's DriftSpeed) bounds every displacement.
  // Recorded again when the bound reaches half the near skin and after a rebuild. Never
  // carried from one call to the next (the state may be edited in between).
  struct NearTrack {
    bool on, valid = false;
    double moved = 0.0;  // bound on any particle's displacement since the recording
    DriftSpeed speed;
    explicit NearTrack(bool use) : on(use) {}
    DriftSpeed* drift_speed() { return on ? &speed : nullptr; }
  };
  // Runs shorter than this record the list more often than they read it.
  static constexpr long kNearMinSteps = 16;
  // Whether the near list's stream serves this model's force passes (near_rows(); the
  // host one-pass kernel asks near_stream_usable() too, kernels/dem/contact_forces.hpp).
  bool stream_reads() const {
#if GRANULAR_CONTACT_BATCH
    return !two_pass() && params_.near_stream && params_.batched_contacts &&
           near_stream_usable(model_);
#else
    return false;
#endif
  }
  // The particles' packed records for the frictional stream (DemParams::packed_stream), sized
  // for the particles, where this system's force passes may read them; null elsewhere. Written
  // by each kick-drift pass of a run that tracks the near list, read by the force passes that
  // take the stream in that run's steps (the drift's values: between the two, a read step
  // neither strains nor rebuilds).
  double* packed_records() {
    if (!params_.packed_stream || !stream_reads() || Model::history == 0 || mc_.active() ||
        p_.n < params_.packed_stream_min_particles)
      return nullptr;
    constexpr long S = ParticlePack::kStride;
    if (pack_.extent(0) != static_cast<size_t>(S * p_.n))
      pack_ = pack_view(Kokkos::view_alloc("dem::particle_pack", Kokkos::WithoutInitializing),
                        S * p_.n);
    if (reinterpret_cast<std::uintptr_t>(pack_.data()) % 32 != 0)  // aligned loads read it
      throw std::logic_error("DemSystem: the packed particle records are not 32-byte aligned");
    return pack_.data();
  }
  double near_skin() const {
    if (params_.near_skin >= 0) return params_.near_skin;
    return params_.skin / (stream_reads() && Model::history > 0 ? 32 : 16);
  }
  // A straining box moves every pair affinely (the list's skin test knows; the near list's
  // does not): no near list there.
  bool near_usable(long n, bool straining) const {
    return !two_pass() && !straining && n >= kNearMinSteps && near_skin() > 0.0;
  }
  // Whether this step's force pass reads the near list (Use) or records it (Record), after
  // the drift of the step (whose speed kick_drift measured).
  NearMode near_mode(NearTrack& t) {
    if (!t.on) return NearMode::Record;
    // A position is rounded to the last bit of its coordinate (at most 1e-15 of the box's
    // farthest coordinate), and dt |v| by a relative 1e-16; the margins cover both, and the
    // round-off of the distances the near skin is tested with.
    double extent = 0.0;
    for (int d = 0; d < 3; ++d) extent = std::max(extent, std::fabs(box_.lo[d]) + box_.len[d]);
    t.moved += params_.dt * std::sqrt(t.speed.max_v2) * (1.0 + 1e-12) + 1e-15 * extent;
    if (t.valid && 2.0 * t.moved < near_skin() * (1.0 - 1e-9)) {  // false for NaN
      ++near_use_.reads;
      return NearMode::Use;
    }
    ++near_use_.recordings;
    t.valid = true, t.moved = 0.0;
    return NearMode::Record;
  }
  // Room for the near list's rows (host one-pass kernel): one slot per owned entry.
  // `tracked`: the near list is kept within this call of step() (NearTrack::on), so its stream
  // may be recorded and read too.
  NearRows near_rows(bool tracked) {
    if (two_pass()) return NearRows();
    if (near_k_.extent(0) < static_cast<size_t>(nl_.num_pairs()) || near_k_.extent(0) == 0)
      near_k_ = int_view(Kokkos::view_alloc("dem::near_entries", Kokkos::WithoutInitializing),
                         nl_.num_pairs() + nl_.num_pairs() / 8 + 16);
    if (near_count_.extent(0) != static_cast<size_t>(p_.n))
      near_count_ = int_view("dem::near_count", p_.n);
    NearRows r;
    r.k = near_k_.data(), r.count = near_count_.data(), r.skin = near_skin();
    if (tracked && params_.near_stream) r.stream = &near_stream_;
    return r;
  }
  // `started`: f and torque already hold the damping terms (kick_drift with damping_start()).
  // `near`: whether the pass reads the near list or records it (near_mode()).
  // `tracked`: see near_rows().
  // `pack`: the packed records this step's kick-drift pass wrote (packed_records()), read
  // where the pass takes the frictional stream.
  void forces(double dt, bool started = false, NearMode near = NearMode::Record,
              bool tracked = false, const double* pack = nullptr) {
    if (params_.mixed_precision) fixed_.update(p_, box_);
    if (mc_.active()) {  // run-time dispatch here, compile-time switches inside the kernels
      mc_.compute(p_, nl_, history_view(), pair_, box_, model_, params_.damping, rate_, dt, walls_,
                  wall_history_, wall_record_, params_.gravity, external_,
                  params_.batched_contacts);
      return;
    }
    NearRows rows = near_rows(tracked);
    if (near == NearMode::Use) rows.pack = pack;
    compute_forces(p_, nl_, history_view(), pair_, box_, model_, params_.damping, rate_, dt,
                   two_pass(), rows, near, params_.batched_contacts,
                   params_.contact_thread_per_particle, started,
                   params_.flag_apart_rows ? row_flags_ : RowFlags<ExecSpace>(),
                   params_.mixed_precision ? &fixed_ : nullptr);
    if (external_)
      add_external_forces(p_, walls_.view(), walls_.size(), wall_history_, wall_record_, model_,
                          params_.gravity, dt);
  }
  // Forces of a state whose contacts have no previous evaluation under the current law.
  void initial_forces() {
    forces(0.0);
    if (mc_.options().mode == MultiContact::Strain) forces(0.0);
  }

  void step_profiled(long n) {
    const double dt = params_.dt;
    const bool straining = rate_[0] != 0.0 || rate_[1] != 0.0 || rate_[2] != 0.0;
    Kokkos::Timer timer;
    auto lap = [&](double& acc) {
      Kokkos::fence();
      acc += timer.seconds();
      timer.reset();
    };
    const DampingStart damp = damping_start();
    NearTrack near(near_usable(n, straining));
    double* pack = near.on ? packed_records() : nullptr;
    Kokkos::fence();
    timer.reset();
    for (long s = 0; s < n; ++s) {
      const double max_sq =
          kick_drift<kRot>(p_, box_, nl_.reference(), dt, false, damp, near.drift_speed(), pack);
      lap(profile_->integrate);
      if (straining) apply_affine_strain(p_, nl_.reference(), box_, rate_, dt);
      lap(profile_->strain);
      if (rebuild_due(max_sq)) {
        rebuild();
        near.valid = false;
        if (pack) pack = packed_records();
        ++profile_->rebuilds;
      }
      lap(profile_->neighbor);
      walls_.update(time_ + dt);
      forces(dt, damp.on, near_mode(near), near.on, pack);
      lap(profile_->force);
      kick<kRot>(p_, dt);
      lap(profile_->integrate);
      time_ += dt;
      ++steps_;
    }
  }

  // The two lightest masses of each species (infinity where there are fewer particles).
  using LightestMasses = std::array<std::array<double, 2>, kMaxSpecies>;
  template <class MassView, class SpeciesView>
  LightestMasses lightest_masses(const MassView& mass, const SpeciesView& species) const {
    constexpr double none = std::numeric_limits<double>::infinity();
    LightestMasses light;
    for (auto& l : light) l[0] = l[1] = none;
    for (int i = 0; i < p_.n; ++i) {
      auto& l = light[species(i)];
      if (mass(i) < l[0])
        l[1] = l[0], l[0] = mass(i);
      else if (mass(i) < l[1])
        l[1] = mass(i);
    }
    return light;
  }

  // The shortest contact duration of any pair that can occur, with its stiffness and reduced
  // mass, and the fastest contact dashpot rate.
  struct ShortestContact {
    double tc = std::numeric_limits<double>::infinity(), k = 0, m = 0, rate = 0;
  };
  ShortestContact shortest_contact(const LightestMasses& light) const {
    constexpr double none = std::numeric_limits<double>::infinity();
    const double delta_ref = params_.max_overlap * a_min_, length_max = 2 * a_max_;
    ShortestContact c;
    auto guard = [&](int a, int b, double m_red) {
      const PairMask pair = PairMask::only(a, b);
      const double t = model_.shortest_duration(m_red, delta_ref, length_max, pair);
      if (t < c.tc) c.tc = t, c.k = model_.stiffness(delta_ref, length_max, pair), c.m = m_red;
      c.rate = std::max(c.rate, model_.damping_rate(m_red, delta_ref, length_max, pair));
    };
    for (int a = 0; a < kMaxSpecies; ++a)
      for (int b = a; b < kMaxSpecies; ++b) {
        const double ma = light[a][0], mb = a == b ? light[a][1] : light[b][0];
        if (ma < none && mb < none) guard(a, b, ma * mb / (ma + mb));
      }
    // A wall is a partner of infinite mass: its contacts see the particle's mass itself.
    for (const WallSpec& w : walls_.specs())
      for (int a = 0; a < kMaxSpecies; ++a)
        if (light[a][0] < none) guard(a, w.material, light[a][0]);
    return c;
  }

  // The refusal of a time step above dt_guard t_c, saying what to change.
  [[noreturn]] void refuse_time_step(const ShortestContact& c, double stiffer) const {
    const double tc = c.tc;
    std::ostringstream msg;
    msg.precision(4);
    msg << "time step dt = " << params_.dt << " exceeds t_c/" << 1.0 / params_.dt_guard << " = "
        << params_.dt_guard * tc << " for the stiffest, lightest contact of the scene (stiffness "
        << c.k << ", reduced mass " << c.m << ", contact duration " << tc;
    if (stiffer > 1)
      msg << ", with MC-stress's allowance of " << stiffer
          << " x the pair law's stiffness for beta = " << mc_.options().beta
          << " and the overlap limit " << params_.max_overlap;
    msg << "): ";
    if (params_.dt_hint.empty())
      msg << "set " << params_.dt_key << " <= " << params_.dt_guard * tc << " (t_c/50 = " << tc / 50
          << " is the usual choice)";
    else
      msg << params_.dt_hint;
    // A law whose stiffness grows with the overlap is taken at the overlap limit.
    const double delta_ref = params_.max_overlap * a_min_, length_max = 2 * a_max_;
    if (model_.stiffness(0.25 * delta_ref, length_max) < model_.stiffness(delta_ref, length_max))
      msg << "; the stiffness is taken at the overlap limit max_overlap = " << params_.max_overlap
          << " of the smaller radius (a lower limit, where the run's overlaps stay below it, "
             "bounds it lower)";
    throw PhysicsError(msg.str());
  }

  // Explicit dashpots: a rate gamma/m with gamma dt / m above 1 flips the relative velocity
  // every step (above 2 it grows): contact dashpots on their pair's mass, the background
  // and rotational damping on the lightest particle's mass and moment of inertia.
  template <class MassView>
  void check_damping_rates(double contact_rate, const MassView& mass) const {
    constexpr double none = std::numeric_limits<double>::infinity();
    auto refuse = [&](const std::string& what, double value, const std::string& change) {
      std::ostringstream msg;
      msg.precision(4);
      msg << what << " times dt = " << params_.dt << " is " << value
          << ", above 1: the explicit step overshoots (the velocity changes sign each step); "
          << change;
      throw PhysicsError(msg.str());
    };
    if (contact_rate * params_.dt > 1)
      refuse("the fastest contact dashpot rate gamma/m = " + std::to_string(contact_rate),
             contact_rate * params_.dt,
             "lower the contact's damping (gamma_n, gamma_t) or " + params_.dt_key);
    auto inertia = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p_.inertia);
    double m_min = none, i_min = none;
    for (int i = 0; i < p_.n; ++i)
      m_min = std::min(m_min, mass(i)), i_min = std::min(i_min, inertia(i));
    if (params_.damping.translational * params_.dt / m_min > 1)
      refuse("the background damping over the lightest mass",
             params_.damping.translational * params_.dt / m_min,
             "lower the background damping (damping.background) or " + params_.dt_key);
    if (model_.rotations && params_.damping.rotational * params_.dt / i_min > 1)
      refuse("the rotational damping over the smallest moment of inertia",
             params_.damping.rotational * params_.dt / i_min,
             "lower the rotational damping (damping.rotational) or " + params_.dt_key);
  }

  // The stiffest, lightest contact that can occur sets the shortest collision; dt must
  // resolve it. Each species pair that can touch is guarded with its own lightest reduced
  // mass: a pair needs a particle of each species (two of a species for a like pair), a wall
  // touches particles only. A pair that cannot occur (a stiff target sphere alone) is not
  // guarded.
  void check_time_step() const {
    if (p_.n < 1 || (p_.n < 2 && walls_.size() == 0)) return;
    auto mass = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p_.mass);
    auto species = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), p_.species);
    ShortestContact c = shortest_contact(lightest_masses(mass, species));
    // A multi-contact law stiffens the contacts beyond the pair law (multicontact.hpp).
    const double stiffer = stiffness_factor(mc_.options(), params_.max_overlap);
    c.tc /= std::sqrt(stiffer), c.k *= stiffer;
    if (params_.dt > params_.dt_guard * c.tc) refuse_time_step(c, stiffer);
    check_damping_rates(c.rate, mass);
  }

  Particles<ExecSpace> p_;
  PeriodicBox box_;
  Model model_;
  DemParams params_;
  NeighborList<ExecSpace> nl_;
  double rate_[3] = {0, 0, 0};
  double time_ = 0.0;
  long steps_ = 0;
  double particle_volume_ = 0.0;
  double a_min_ = 1e300, a_max_ = 0.0;
  history_type history_;
  typename ContactHistory<ExecSpace, Model::history>::values_view dummy_history_{"dem::no_history",
                                                                                 1, 1};
  StepProfile* profile_ = nullptr;
  WallSet<ExecSpace> walls_;
  wall_view wall_history_;
  WallRecord<ExecSpace> wall_record_;  // what the walls felt (kernels/dem/wall_record.hpp)
  bool external_ = false;  // walls or gravity: one more pass over the particles per step
  using pair_view = Kokkos::View<double**, Kokkos::LayoutRight, typename ExecSpace::memory_space>;
  pair_view pair_;  // per-contact force and torques, written by the owner, gathered by both
  RowFlags<ExecSpace> row_flags_;  // pair rows: whether the contact touched (flag_apart_rows)
  MultiContactForces<ExecSpace> mc_;
  using int_view = Kokkos::View<int*, typename ExecSpace::memory_space>;
  int_view near_k_, near_count_;  // the near list's rows (host one-pass kernel)
  NearStream near_stream_;        // and their stream (kernels/cpu/near_stream.hpp)
  using pack_view = Kokkos::View<double*, Kokkos::HostSpace>;
  pack_view pack_;  // the particles' packed records for the stream (packed_records())
  FixedPositions<ExecSpace> fixed_;  // the force pass's positions (mixed precision)
  NearListUse near_use_;
};

}  // namespace granular
