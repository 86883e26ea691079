// Scene `mixture_moduli`: elastic moduli of glass-rubber (stiff-soft) mixtures against the
// rubber volume fraction and the confining pressure (docs/model_mixtures_and_waves.md §2,
// "M(P, nu_r) tables"). Per mixture: a random gas in a periodic box, compressed to jamming,
// then driven by an isotropic pressure servo through the listed pressures in ascending order (one
// sample, loading branch; or, with preparation.unload_from, up to that pressure first and then
// down through them in descending order: the unloading branch); at each pressure the relaxed state
// is probed like the element tests of `elastic_moduli` (K from isotropic, G from pure-shear, M from
// uniaxial strain, sliding switched off), next to K + 4G/3, the packing's bulk density and V_p =
// sqrt(M/rho). Per mixture M ∝ P^n is fitted. The pair rule for unlike species (harmonic 2pq/(p +
// q) or the source's pq/(p + q)) is compared on one mixture: the same packing re-probed with the
// other rule, and a packing prepared and probed with it.
//
// Keys (besides [materials.*] and [contact] pair_rule, tangential_law, see
// mixture_materials.hpp):
//   [mixture]      stiff_material = "glass"   soft_material = "rubber"
//                  soft_volume_fractions = [0, 0.1, ...]
//   [particles]    count   diameter_min   diameter_max   seed
//                  or from (a packing file: LAMMPS data, H5MD, or an .h5 state group
//                  from_group = "/final_state") with from_materials = ["glass", "rubber"]
//                  (the material of the file's species 0, 1, ...): one mixture, the file's
//                  own, instead of soft_volume_fractions (mixture_gas.hpp)
//   [preparation]  phi_gas = 0.3   phi_0 = 0.55 (end of the fast gas compression)
//                  gas_strain_rate (volumetric, per us)   gas_relax_time (us)
//                  approach_strain_rate (from phi_0 until P reaches the first pressure)
//                  pressures = [...] (MPa)   tolerance   ekin_ratio   response_crossings
//                  max_step   check_crossings   max_checks   max_phase_steps
//                  unload_from (MPa, optional: the peak of the unloading branch)
//   [damping]      gas_time (us, background damping time of the gas stages)
//                  crossing_fraction (background damping time in crossing times, afterwards)
//   [probe]        amplitude   strain_crossings   relax_crossings   keep_friction = false
//   [pair_rule_check] soft_volume_fraction   pressures (subsets of the lists above)
//   [analysis]     skeleton = false (pressure shares, contacts per particle by contact type
//                  and the stiff network's percolation of every state: mixture_skeleton.hpp)
//   [run]          dt   skin   max_overlap   rattler_threshold
#include <Kokkos_Core.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>

#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "core/run/ensemble.hpp"
#include "core/run/finite.hpp"
#include "core/run/progress.hpp"
#include "scenarios/common/config_state.hpp"
#include "scenarios/common/element_test.hpp"
#include "scenarios/common/identity_order.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/common/packing_file.hpp"
#include "scenarios/common/power_law_fit.hpp"
#include "scenarios/common/pressure_servo.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/moduli/moduli_outputs.hpp"
#include "scenarios/moduli/study_units.hpp"
#include "scenarios/scene_registry.hpp"
#include "scenarios/waves/mixture_gas.hpp"
#include "scenarios/waves/mixture_materials.hpp"
#include "scenarios/waves/mixture_skeleton.hpp"

namespace granular {

namespace {
using Exec = Kokkos::DefaultExecutionSpace;
using System = DemSystem<Exec, MixtureModel>;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// One prepared sample: a soft fraction, a pair rule and the pressures it is taken to.
struct Variant {
  double soft_fraction = 0;
  std::string rule;
  std::vector<double> pressures;
  std::string tag;
};

struct Setup {
  MixtureMaterials mats;
  int stiff = 0, soft = 1;
  std::vector<double> fractions;
  GasSpec gas;
  std::optional<HostParticles> from;  // particles.from: the packing file's particles and box
  PeriodicBox from_box;
  double phi0 = 0.55, gas_rate = 0, gas_relax_time = 0, approach_rate = 0;
  std::vector<double> pressures;
  double unload_from = 0;  // > 0: the unloading branch from this peak pressure (MPa)
  ServoSettings servo;
  bool probe_unconverged = false;  // probe a state the servo did not bring to its target
  double gas_damping_time = 0, damping_crossings = 0.5;
  double amplitude = 2e-6, strain_crossings = 1, relax_crossings = 2;
  bool keep_friction = false;
  bool skeleton = false;  // measure the load-bearing skeleton of every state
  double check_fraction = kNaN;
  std::vector<double> check_pressures;
  std::string other_rule;
  DemParams params;
  std::vector<Variant> variants;
};

bool listed(const std::vector<double>& list, double v) {
  return std::any_of(list.begin(), list.end(), [v](double x) { return std::fabs(x - v) < 1e-12; });
}

// The two materials and the particles: a packing file, or a gas and its soft fractions.
void read_particles(const SceneFile& s, Setup& u) {
  u.mats = MixtureMaterials::read(s);
  u.stiff = u.mats.slot(s, "mixture.stiff_material", s.text("mixture.stiff_material"));
  u.soft = u.mats.slot(s, "mixture.soft_material", s.text("mixture.soft_material"));
  s.require(u.stiff != u.soft, "mixture.soft_material", "must differ from mixture.stiff_material");
  GasSpec& g = u.gas;
  g.density = 1.0;  // per particle from its material
  if (s.has("particles.from")) {
    refuse_beside_packing(
        s,
        {"particles.count", "particles.diameter_min", "particles.diameter_max", "particles.seed",
         "preparation.phi_gas", "mixture.soft_volume_fractions"},
        "particles.from", "the particles and their mixture");
    u.from = mixture_from_file(s, u.mats, u.stiff, u.soft, u.from_box);
    u.fractions = {soft_volume_fraction(*u.from, u.soft)};
  } else {
    u.fractions = s.reals("mixture.soft_volume_fractions");
    s.require(!u.fractions.empty(), "mixture.soft_volume_fractions",
              "needs at least one volume fraction");
    for (double f : u.fractions)
      s.require(f >= 0 && f <= 1, "mixture.soft_volume_fractions", "must lie in [0, 1]");
    g.count = s.count("particles.count", 16, kDemBytesPerParticle);
    g.diameter_min = s.real("particles.diameter_min");
    g.diameter_max = s.real("particles.diameter_max");
    g.seed = static_cast<std::uint64_t>(s.integer("particles.seed", 1));
    g.phi = s.real("preparation.phi_gas", 0.3);
    check_gas(s, g, "preparation.phi_gas");
  }
}

// The compression to phi_0 and the pressures of the branch.
void read_loading(const SceneFile& s, Setup& u) {
  u.phi0 = s.real("preparation.phi_0", 0.55);
  s.require(u.phi0 > (u.from ? 0.0 : u.gas.phi) && u.phi0 < 0.6, "preparation.phi_0",
            u.from ? "must lie in (0, 0.6) (below frictional jamming)"
                   : "must lie between preparation.phi_gas and 0.6 (below frictional jamming)");
  u.gas_rate = s.real("preparation.gas_strain_rate");
  u.gas_relax_time = s.real("preparation.gas_relax_time");
  u.approach_rate = s.real("preparation.approach_strain_rate");
  s.require(u.gas_rate > 0 && u.gas_rate < 0.1, "preparation.gas_strain_rate",
            "must lie in (0, 0.1) per us");
  s.require(u.gas_relax_time >= 0, "preparation.gas_relax_time", "must not be negative");
  s.require(u.approach_rate > 0 && u.approach_rate <= u.gas_rate,
            "preparation.approach_strain_rate", "must lie in (0, preparation.gas_strain_rate]");
  u.pressures = s.reals("preparation.pressures");
  s.require(!u.pressures.empty(), "preparation.pressures", "needs at least one pressure");
  // Read only where given, so that the summaries of loading-branch runs stay as they were.
  if (s.has("preparation.unload_from")) {
    u.unload_from = s.real("preparation.unload_from", 0.0);
    s.require(u.unload_from > u.pressures.front() && std::isfinite(u.unload_from),
              "preparation.unload_from",
              "must exceed the first (highest) of preparation.pressures: the unloading branch "
              "starts above them");
  }
  for (size_t k = 0; k < u.pressures.size(); ++k) {
    s.require(u.pressures[k] > 0, "preparation.pressures", "must be positive (MPa)");
    if (u.unload_from > 0)
      s.require(k == 0 || u.pressures[k] < u.pressures[k - 1], "preparation.pressures",
                "must decrease with preparation.unload_from (one sample is taken down "
                "through them: the unloading branch)");
    else
      s.require(k == 0 || u.pressures[k] > u.pressures[k - 1], "preparation.pressures",
                "must increase (one sample is taken up through them: the loading branch; "
                "preparation.unload_from takes it down through decreasing ones)");
  }
}

// The pressure servo.
void read_servo(const SceneFile& s, Setup& u) {
  ServoSettings& sv = u.servo;
  sv.tolerance = s.real("preparation.tolerance", 0.02);
  sv.ekin_ratio = s.real("preparation.ekin_ratio", 1e-6);
  sv.response_crossings = s.real("preparation.response_crossings", 2.0);
  sv.max_step = s.real("preparation.max_step", 0.002);
  sv.check_crossings = s.real("preparation.check_crossings", 0.25);
  // Read only where given, so that the summaries of runs without it (every committed
  // reference) stay as they were.
  if (s.has("preparation.integral_crossings"))
    sv.integral_crossings = s.real("preparation.integral_crossings", 0.0);
  sv.max_cycles = s.small_integer("preparation.max_checks", 2000);
  sv.max_phase_steps = s.integer("preparation.max_phase_steps", 50000);
  u.probe_unconverged = s.flag("preparation.probe_unconverged", false);
  s.require(sv.tolerance > 0 && sv.tolerance < 0.5, "preparation.tolerance",
            "must lie in (0, 0.5)");
  s.require(sv.ekin_ratio > 0, "preparation.ekin_ratio", "must be positive");
  s.require(sv.response_crossings > 0, "preparation.response_crossings", "must be positive");
  s.require(sv.max_step > 0 && sv.max_step < 0.1, "preparation.max_step", "must lie in (0, 0.1)");
  s.require(sv.check_crossings > 0 && sv.check_crossings <= 1e3, "preparation.check_crossings",
            "must lie in (0, 1000] crossing times");
  s.require(sv.max_cycles >= 1, "preparation.max_checks", "must be at least 1");
  s.require(sv.integral_crossings >= 0 && std::isfinite(sv.integral_crossings),
            "preparation.integral_crossings", "must be 0 (no integral action) or positive");
  s.require(sv.max_phase_steps >= sv.min_phase_steps, "preparation.max_phase_steps",
            "must be at least 100");
}

// The damping of the gas and of the servo phases.
void read_damping(const SceneFile& s, Setup& u) {
  u.gas_damping_time = s.real("damping.gas_time");
  u.damping_crossings = s.real("damping.crossing_fraction", 0.5);
  s.require(u.gas_damping_time > 0, "damping.gas_time", "must be positive");
  s.require(u.damping_crossings > 0 && u.damping_crossings <= 1e3, "damping.crossing_fraction",
            "must lie in (0, 1000] crossing times");
}

// The probes.
void read_probe(const SceneFile& s, Setup& u) {
  u.amplitude = s.real("probe.amplitude", 2e-6);
  u.strain_crossings = s.real("probe.strain_crossings", 1.0);
  u.relax_crossings = s.real("probe.relax_crossings", 2.0);
  u.keep_friction = s.flag("probe.keep_friction", false);
  // Read only where given, so that the summaries of scenes without it stay as they were.
  if (s.has("analysis.skeleton")) u.skeleton = s.flag("analysis.skeleton", false);
  s.require(u.amplitude > 0 && u.amplitude < 1e-3, "probe.amplitude", "must lie in (0, 1e-3)");
  s.require(u.strain_crossings > 0, "probe.strain_crossings", "must be positive");
  s.require(u.relax_crossings >= 0, "probe.relax_crossings", "must not be negative");
}

// The time step, skin and overlap limit.
void read_run(const SceneFile& s, Setup& u) {
  u.params.dt = s.real("run.dt");
  u.params.dt_key = "run.dt";
  u.params.skin = s.real("run.skin");
  u.params.max_overlap = s.real("run.max_overlap", 0.3);
  u.params.rattler_threshold = s.small_integer("run.rattler_threshold", 4);
  s.require(u.params.dt > 0, "run.dt", "must be positive");
  s.require(u.gas_relax_time / u.params.dt <= 1e8, "preparation.gas_relax_time",
            "must be at most 1e8 time steps of run.dt (hours on one core)");
  s.require(u.params.skin > 0, "run.skin", "must be positive");
  s.require(u.params.max_overlap > 0 && u.params.max_overlap < 0.5, "run.max_overlap",
            "must lie in (0, 0.5)");
}

// The run of one fraction under the other pair rule, where the scene asks for it.
void read_pair_rule_check(const SceneFile& s, Setup& u) {
  u.other_rule = u.mats.pair_rule == "harmonic" ? "product_over_sum" : "harmonic";
  if (s.has("pair_rule_check.soft_volume_fraction") || s.has("pair_rule_check.pressures")) {
    s.require(!u.from, "pair_rule_check.soft_volume_fraction",
              "needs mixture.soft_volume_fractions (not a packing file, particles.from)");
    u.check_fraction = s.real("pair_rule_check.soft_volume_fraction");
    u.check_pressures = s.reals("pair_rule_check.pressures");
    s.require(u.check_fraction > 0 && u.check_fraction < 1 && listed(u.fractions, u.check_fraction),
              "pair_rule_check.soft_volume_fraction",
              "must be one of mixture.soft_volume_fractions strictly between 0 and 1 (a mixture "
              "has unlike contacts)");
    s.require(!u.check_pressures.empty(), "pair_rule_check.pressures",
              "needs at least one pressure");
    for (double p : u.check_pressures)
      s.require(p > 0 && listed(u.pressures, p), "pair_rule_check.pressures",
                "must be positive and listed in preparation.pressures");
    std::sort(u.check_pressures.begin(), u.check_pressures.end());
    // In the order the branch takes them: down from the peak on the unloading branch.
    if (u.unload_from > 0) std::reverse(u.check_pressures.begin(), u.check_pressures.end());
  }
}

// One variant per soft fraction, and the pair-rule check's.
void add_variants(Setup& u) {
  for (double f : u.fractions) {
    char tag[64];
    std::snprintf(tag, sizeof tag, "nu%.3f_%s", f, u.mats.pair_rule.c_str());
    u.variants.push_back({f, u.mats.pair_rule, u.pressures, tag});
  }
  if (!u.check_pressures.empty()) {
    char tag[64];
    std::snprintf(tag, sizeof tag, "nu%.3f_%s", u.check_fraction, u.other_rule.c_str());
    u.variants.push_back({u.check_fraction, u.other_rule, u.check_pressures, tag});
  }
}

Setup read_setup(const SceneFile& s) {
  Setup u;
  read_particles(s, u);
  read_loading(s, u);
  read_servo(s, u);
  read_damping(s, u);
  read_probe(s, u);
  read_run(s, u);
  read_pair_rule_check(s, u);
  s.reject_unknown_keys();
  add_variants(u);
  return u;
}

// The particles a variant starts from: the scene's gas (mixture_gas.hpp), or the packing
// file's particles and box.
HostParticles start_of(const Setup& u, double soft_fraction, PeriodicBox& box) {
  if (u.from) {
    box = u.from_box;
    return *u.from;
  }
  return mixture_gas(u.gas, u.mats, u.stiff, u.soft, soft_fraction, box);
}

double total_mass(const HostParticles& h) {
  double m = 0;
  for (int i = 0; i < h.size(); ++i)
    m += h.density[i] * 4.0 / 3.0 * M_PI * std::pow(h.radius[i], 3);
  return m;
}

double longest_edge(const PeriodicBox& b) { return std::max({b.len[0], b.len[1], b.len[2]}); }

// Background damping with time constant tau (translational m/tau, rotational 0.1 m d^2/tau
// as in the wave scene), for the mean particle mass m and diameter d.
DemParams with_damping(DemParams p, double tau, double m, double d) {
  p.damping.translational = m / tau;
  p.damping.rotational = 0.1 * m * d * d / tau;
  return p;
}

// The gas stage's parameters: damping scaled with this packing's mean mass and diameter.
DemParams gas_params(const Setup& u, const HostParticles& host) {
  double dsum = 0;
  for (int i = 0; i < host.size(); ++i) dsum += 2 * host.radius[i];
  const double dbar = dsum / host.size(), mbar = total_mass(host) / host.size();
  return with_damping(u.params, u.gas_damping_time, mbar, dbar);
}

MixtureModel with_friction(MixtureModel m, double mu) {
  for (auto& row : m.tangential.table.p)
    for (auto& q : row) q.mu_s = q.mu_d = mu;
  return m;
}
MixtureModel without_sliding(const MixtureModel& m) { return with_friction(m, INFINITY); }

struct Probed {
  Moduli mod;
  double reversal = kNaN;
  long strain_steps = 0, relax_steps = 0;
};

Probed probe_state(const ConfigState& c, const MixtureModel& model, const DemParams& params,
                   const Setup& u, double tc) {
  Probed r;
  const ServoSettings bounds = u.servo;
  r.strain_steps = phase_steps(u.strain_crossings, tc, params.dt, bounds);
  r.relax_steps = u.relax_crossings > 0 ? phase_steps(u.relax_crossings, tc, params.dt, bounds) : 0;
  auto make = [&] { return restart_system<System>(c, model, params); };
  r.mod = probe_moduli_restarting(make, u.amplitude, r.strain_steps, r.relax_steps, &r.reversal);
  return r;
}

// The skeleton of the state `sys` holds (mixture_skeleton.hpp).
Skeleton skeleton_of(const System& sys, int stiff) {
  const ParticleRows p = gather_by_identity(sys.particles());
  return measure_skeleton(contact_network(sys), p.species, p.position, sys.box().len, stiff);
}

// The skeleton as columns of a table row.
void add_skeleton_columns(const Skeleton& k, std::map<std::string, double>& row) {
  row["skeleton_share_stiff_stiff"] = k.share[0];
  row["skeleton_share_stiff_soft"] = k.share[1];
  row["skeleton_share_soft_soft"] = k.share[2];
  row["skeleton_z_stiff_stiff"] = k.z_stiff_stiff;
  row["skeleton_z_stiff_soft"] = k.z_stiff_soft;
  row["skeleton_z_soft_stiff"] = k.z_soft_stiff;
  row["skeleton_z_soft_soft"] = k.z_soft_soft;
  row["skeleton_stiff_largest_cluster"] = k.largest_cluster;
  row["skeleton_stiff_wrapping_axes"] = k.wrapping_axes;
}

// The models of a variant: the one it is prepared with, the one it is probed with, and the
// other rule's probing model where the same packing is probed with it too (the probing
// model alone differs).
struct VariantModels {
  MixtureModel model, probe, other_probe;
  bool reprobe = false;
};
VariantModels variant_models(const Setup& u, const Variant& v) {
  VariantModels r;
  r.model = u.mats.model(v.rule);
  r.probe = u.keep_friction ? r.model : without_sliding(r.model);
  r.reprobe = v.rule == u.mats.pair_rule && v.soft_fraction == u.check_fraction;
  const MixtureModel other = u.mats.model(u.other_rule);
  r.other_probe = u.keep_friction ? other : without_sliding(other);
  return r;
}

// A variant's sample as it is taken through its pressures: the system, and the particles'
// total mass, mean diameter and mass and solid density.
struct Sample {
  PeriodicBox box;
  HostParticles host;
  double mass = 0, dbar = 0, mbar = 0, rho_solid = 0;
  std::optional<System> sys;
};

// The variant's gas, brought to its first pressure (the peak of an unloading branch): a fast
// compression to phi_0, a relaxation, then a slower one until the packing carries that
// pressure (the servo takes over from there). A packing file already denser than phi_0 skips
// the fast compression (strain_to_phi returns at once).
void compress_gas(const Setup& u, const Variant& v, const MixtureModel& model, Sample& p) {
  p.host = start_of(u, v.soft_fraction, p.box);
  const HostParticles& host = p.host;
  p.mass = total_mass(host);
  double dsum = 0, vsolid = 0;
  for (int i = 0; i < host.size(); ++i)
    dsum += 2 * host.radius[i], vsolid += 4.0 / 3.0 * M_PI * std::pow(host.radius[i], 3);
  p.dbar = dsum / host.size(), p.mbar = p.mass / host.size();
  p.rho_solid = p.mass / vsolid;
  p.sys.emplace(Particles<Exec>::from_host(host), p.box, model, gas_params(u, host));
  strain_to_phi(*p.sys, u.phi0, -u.gas_rate / 3, 500, nullptr);
  p.sys->step(static_cast<long>(std::ceil(u.gas_relax_time / u.params.dt)));
  const double peak = u.unload_from > 0 ? u.unload_from : v.pressures.front();
  compress_to_pressure(*p.sys, peak, u.approach_rate, 20, 0.74);
}

// The servo's run to one target, and the parameters (damping) it ran with.
struct Settled {
  DemParams params;
  ServoResult servo;
};

// Brings the sample to `target` with the pressure servo, its damping scaled with the crossing
// time this packing will have at the target (K ∝ P^{1/3} for Hertz, so t_c ∝ P^{-1/6}).
Settled settle(const Setup& u, const MixtureModel& model, double target, Sample& p) {
  const Measurements m = p.sys->measure();
  const double rho = p.mass / p.sys->box().volume();
  double tc = crossing_time(m, rho, longest_edge(p.sys->box()));
  if (std::isfinite(tc) && m.pressure > 0) tc *= std::pow(m.pressure / target, 1.0 / 6.0);
  if (!std::isfinite(tc)) tc = u.servo.max_phase_steps * u.params.dt;
  Settled r;
  r.params = with_damping(u.params, u.damping_crossings * tc, p.mbar, p.dbar);
  {
    const ConfigState c = snapshot(*p.sys, p.host.density, m.pressure);
    p.sys.emplace(restart_system<System>(c, model, r.params));
  }
  r.servo = servo_to_pressure(*p.sys, target, rho, u.servo);
  return r;
}

// The unloading branch starts from a relaxed state at its peak pressure (not probed).
void settle_at_peak(const Setup& u, const Variant& v, const MixtureModel& model, Sample& p) {
  const ServoResult sr = settle(u, model, u.unload_from, p).servo;
  if (!sr.converged)
    std::cerr << v.tag
              << ": the servo did not settle at the unloading branch's peak P = " << u.unload_from
              << " MPa within " << u.servo.max_cycles
              << " checks; the branch goes down from P = " << sr.m.pressure << " MPa\n";
}

// What one state of a variant gave: the servo's run to its target, the state's measurements,
// bulk density and crossing time, whether it is jammed and was probed, its moduli (and M
// under the other rule, where the check asks for it) and its skeleton.
struct MixtureState {
  double target = 0;
  ServoResult servo;
  Measurements m;
  double rho = 0, rho_solid = 0, tc = 0, damping_time = 0;
  int particles = 0;
  bool jammed = false, probed = false;
  Probed probe;
  double M_other = kNaN;
  std::optional<Skeleton> skeleton;
};

// A state the servo left short of its target, or still moving: said on the console.
void report_unconverged(const Setup& u, const Variant& v, const MixtureState& s) {
  std::cerr << v.tag << ": the servo did not reach P = " << s.target << " MPa within "
            << u.servo.max_cycles << " checks (P = " << s.m.pressure
            << ", E_kin/E_pot = " << s.servo.ekin_ratio << " against " << u.servo.ekin_ratio
            << "); "
            << (s.probed ? "probed as it is (preparation.probe_unconverged)"
                         : "not probed: raise preparation.max_checks, or set "
                           "preparation.probe_unconverged = true to probe it as it is")
            << "\n";
}

// Measures and probes the state the servo left the sample in at `target`.
MixtureState measure_state(const Setup& u, const Variant& v, const VariantModels& models,
                           const Sample& p, double target, const Settled& settled) {
  MixtureState s;
  const ServoResult& sr = settled.servo;
  s.target = target, s.servo = sr, s.m = sr.m;
  s.rho = p.mass / p.sys->box().volume(), s.rho_solid = p.rho_solid;
  s.tc = crossing_time(s.m, s.rho, longest_edge(p.sys->box()));
  s.damping_time = u.damping_crossings * s.tc;
  const ConfigState c = snapshot(*p.sys, p.host.density, s.m.pressure);
  s.particles = c.size();
  // A state the servo brought to rest at its target carries that pressure: it is jammed
  // whatever share of its beads rattle (soft beads much smaller than the stiff ones sit in
  // its pores by the thousand; is_jammed's count, at most half the particles rattling, is
  // meant for one size).
  s.jammed = (is_jammed(s.m) || (sr.converged && s.m.z_corrected > 0)) && std::isfinite(s.tc);
  // A state the servo left short of its target, or still moving, is not the state asked
  // for: its moduli are not measured (NaN) and it is left out of the fits, unless the scene
  // asks for it to be probed as it is.
  s.probed = s.jammed && (sr.converged || u.probe_unconverged);
  if (!sr.converged) report_unconverged(u, v, s);
  if (s.probed) s.probe = probe_state(c, models.probe, settled.params, u, s.tc);
  if (s.probed && models.reprobe && listed(u.check_pressures, target))
    s.M_other = probe_state(c, models.other_probe, settled.params, u, s.tc).mod.M;
  if (u.skeleton) s.skeleton = skeleton_of(*p.sys, u.stiff);
  return s;
}

// The table row of one state.
std::map<std::string, double> state_row(const Variant& v, const MixtureState& s) {
  const Measurements& m = s.m;
  const Moduli& mod = s.probe.mod;
  const bool probed = s.probed;
  const double unmeasured = s.jammed ? kNaN : 0.0;
  const double mkg = mod.K + 4 * mod.G / 3;
  std::map<std::string, double> row = {
      {"soft_fraction", v.soft_fraction},
      {"pair_rule_product_over_sum", v.rule == "product_over_sum" ? 1.0 : 0.0},
      {"pressure_target", s.target},
      {"pressure", m.pressure},
      {"servo_converged", s.servo.converged ? 1.0 : 0.0},
      {"servo_checks", static_cast<double>(s.servo.cycles)},
      {"servo_steps", static_cast<double>(s.servo.steps)},
      {"ekin_over_epot", s.servo.ekin_ratio},
      {"jammed", s.jammed ? 1.0 : 0.0},
      {"probed", probed ? 1.0 : 0.0},
      {"particles", static_cast<double>(s.particles)},
      {"phi", m.phi},
      {"z_corrected", m.z_corrected},
      {"z_mean", m.z},
      {"rattler_fraction", m.rattlers / m.particles},
      {"max_overlap", m.max_overlap},
      {"rho_bulk", s.rho},
      {"rho_solid", s.rho_solid},
      {"crossing_time", s.tc},
      {"damping_time", s.damping_time},
      {"probe_strain_steps", static_cast<double>(s.probe.strain_steps)},
      {"probe_relax_steps", static_cast<double>(s.probe.relax_steps)},
      // No contact network: no stiffness (0); a network not probed: not measured (NaN).
      {"K", probed ? mod.K : unmeasured},
      {"G", probed ? mod.G : unmeasured},
      {"M", probed ? mod.M : unmeasured},
      {"M_KG", probed ? mkg : unmeasured},
      {"M_over_M_KG", probed ? mod.M / mkg : kNaN},
      {"Vp", probed && mod.M > 0 ? 1000.0 * std::sqrt(mod.M / s.rho) : unmeasured},  // m/s
      {"isotropic_reversal_residual", s.probe.reversal},
      {"M_other_rule_same_packing", s.M_other},
  };
  if (s.skeleton) add_skeleton_columns(*s.skeleton, row);
  return row;
}

// The console line of one state (with the progress line shown).
void report_state(const Variant& v, const MixtureState& s, std::map<std::string, double> row,
                  const Progress& progress) {
  char line[256];
  std::snprintf(line, sizeof line,
                "%s  P %.4g MPa (target %.4g, %d checks)  phi %.4f  Z %.3f  K %.4g  G %.4g  "
                "M %.4g MPa  M/(K+4G/3) %.4f  Vp %.0f m/s\n",
                v.tag.c_str(), s.m.pressure, s.target, s.servo.cycles, s.m.phi, s.m.z_corrected,
                row["K"], row["G"], row["M"], row["M_over_M_KG"], row["Vp"]);
  if (progress.enabled()) std::cerr << line;
}

// Prepares one variant and probes it at each of its pressures; returns its states in order.
std::vector<MixtureState> run_variant(const Setup& u, const Variant& v, Progress& progress,
                                      long& done) {
  const VariantModels models = variant_models(u, v);
  Sample p;
  compress_gas(u, v, models.model, p);
  if (u.unload_from > 0) settle_at_peak(u, v, models.model, p);
  std::vector<MixtureState> states;
  for (double target : v.pressures) {
    const Settled settled = settle(u, models.model, target, p);
    states.push_back(measure_state(u, v, models, p, target, settled));
    progress.update(++done);
    report_state(v, states.back(), state_row(v, states.back()), progress);
  }
  return states;
}

// A variant's states as its part of the study's outputs (its checkpoint).
ModuliOutputs variant_part(const Variant& v, const std::vector<MixtureState>& states) {
  ModuliOutputs part;
  for (const MixtureState& s : states) part.add_row(v.tag, state_row(v, s));
  return part;
}

// Units of the table's columns (state_row's) in results.h5; a column without one is
// a programming error (std::logic_error), found before anything is written.
std::string table_unit(const std::string& column) {
  static const std::map<std::string, std::string> units = {
      {"soft_fraction", "1"},
      {"pair_rule_product_over_sum", "1"},
      {"skeleton_share_stiff_stiff", "1"},
      {"skeleton_share_stiff_soft", "1"},
      {"skeleton_share_soft_soft", "1"},
      {"skeleton_z_stiff_stiff", "1"},
      {"skeleton_z_stiff_soft", "1"},
      {"skeleton_z_soft_stiff", "1"},
      {"skeleton_z_soft_soft", "1"},
      {"skeleton_stiff_largest_cluster", "1"},
      {"skeleton_stiff_wrapping_axes", "1"},
      {"pressure_target", "MPa"},
      {"pressure", "MPa"},
      {"servo_converged", "1"},
      {"servo_checks", "1"},
      {"servo_steps", "1"},
      {"ekin_over_epot", "1"},
      {"jammed", "1"},
      {"probed", "1"},
      {"particles", "1"},
      {"phi", "1"},
      {"z_corrected", "1"},
      {"z_mean", "1"},
      {"rattler_fraction", "1"},
      {"max_overlap", "1"},  // delta / min(a_i, a_j)
      {"rho_bulk", "ug mm-3"},
      {"rho_solid", "ug mm-3"},
      {"crossing_time", "us"},
      {"damping_time", "us"},
      {"probe_strain_steps", "1"},
      {"probe_relax_steps", "1"},
      {"K", "MPa"},
      {"G", "MPa"},
      {"M", "MPa"},
      {"M_KG", "MPa"},
      {"M_over_M_KG", "1"},
      {"Vp", "m s-1"},  // 1000 sqrt(M / rho_bulk): mm/us converted to m/s
      {"isotropic_reversal_residual", "1"},
      {"M_other_rule_same_packing", "MPa"},
  };
  const auto at = units.find(column);
  if (at == units.end())
    throw std::logic_error("results.h5: dataset /table/" + column +
                           " has no unit; add its column to table_unit");
  return at->second;
}

// Units of the fit columns: exponents and their standard errors are pure numbers; the
// prefactor A of y = A P^n, P in MPa, is the modulus at P = 1 MPa.
std::string fit_unit(const std::string& column) {
  if (column == "soft_fraction") return "1";
  const auto ends = [&](const std::string& tail) {
    return column.size() >= tail.size() &&
           column.compare(column.size() - tail.size(), tail.size(), tail) == 0;
  };
  if (ends("_exponent") || ends("_exponent_stderr")) return "1";
  if (ends("_prefactor")) return "MPa";
  throw std::logic_error("results.h5: dataset /fits/" + column +
                         " has no unit; add its column to fit_unit");
}

// Fits of M ∝ P^n (and of K, G, M_KG) per mixture, over its probed configurations: their
// entries of summary.json, and the columns of /fits.
struct PowerLawFits {
  Json json = Json::array();
  std::map<std::string, std::vector<double>> columns;
};
PowerLawFits power_law_fits(const Setup& u, const std::map<std::string, std::vector<double>>& T) {
  const size_t rows = T.at("M").size();
  PowerLawFits out;
  Json& fits = out.json;
  std::map<std::string, std::vector<double>>& fit_cols = out.columns;
  for (const Variant& v : u.variants) {
    if (v.rule != u.mats.pair_rule) continue;
    std::vector<double> P, M, K, G, MKG;
    for (size_t i = 0; i < rows; ++i)
      if (T.at("soft_fraction")[i] == v.soft_fraction &&
          T.at("pair_rule_product_over_sum")[i] == (v.rule == "product_over_sum" ? 1.0 : 0.0) &&
          T.at("probed")[i] > 0) {
        P.push_back(T.at("pressure")[i]), M.push_back(T.at("M")[i]);
        K.push_back(T.at("K")[i]), G.push_back(T.at("G")[i]), MKG.push_back(T.at("M_KG")[i]);
      }
    Json j = Json::object();
    j["soft_fraction"] = v.soft_fraction;
    const std::pair<const char*, const std::vector<double>*> series[] = {
        {"M", &M}, {"K", &K}, {"G", &G}, {"M_KG", &MKG}};
    for (const auto& [name, y] : series) {
      const PowerLawFit f = fit_power_law(P, *y);
      Json fj = Json::object();
      // A fit of too few points (one: no exponent; two: no spread) is undefined, not failed.
      fj["points"] = f.points, fj["exponent"] = Json::or_null(f.exponent);
      fj["exponent_stderr"] = Json::or_null(f.exponent_stderr);
      fj["prefactor_MPa"] = Json::or_null(f.prefactor);
      fj["rms_log_residual"] = Json::or_null(f.rms_log_residual);
      j[std::string("fit_") + name] = fj;
      fit_cols[std::string(name) + "_exponent"].push_back(f.exponent);
      fit_cols[std::string(name) + "_exponent_stderr"].push_back(f.exponent_stderr);
      fit_cols[std::string(name) + "_prefactor"].push_back(f.prefactor);
    }
    fit_cols["soft_fraction"].push_back(v.soft_fraction);
    fits.push(j);
  }

  return out;
}

// The pair-rule comparison at the check fraction and pressures.
Json pair_rule_check(const Setup& u, const std::map<std::string, std::vector<double>>& T) {
  const size_t rows = T.at("M").size();
  Json rule = Json::object();
  rule["soft_volume_fraction"] = u.check_fraction;
  rule["rule"] = u.mats.pair_rule;
  rule["other_rule"] = u.other_rule;
  Json list = Json::array();
  for (double p : u.check_pressures) {
    double M_main = kNaN, M_same = kNaN, M_own = kNaN, P_main = kNaN, P_own = kNaN;
    for (size_t i = 0; i < rows; ++i) {
      if (T.at("soft_fraction")[i] != u.check_fraction || T.at("pressure_target")[i] != p) continue;
      const bool other =
          T.at("pair_rule_product_over_sum")[i] == (u.other_rule == "product_over_sum" ? 1.0 : 0.0);
      if (other) {
        M_own = T.at("M")[i], P_own = T.at("pressure")[i];
      } else {
        M_main = T.at("M")[i], M_same = T.at("M_other_rule_same_packing")[i];
        P_main = T.at("pressure")[i];
      }
    }
    Json e = Json::object();
    e["pressure_target"] = p;
    // A state the check did not reach (unjammed, or no such row) has no modulus: null.
    e["M_rule"] = Json::or_null(M_main), e["pressure_rule"] = Json::or_null(P_main);
    e["M_other_rule_same_packing"] = Json::or_null(M_same);
    e["ratio_same_packing"] = Json::or_null(M_same / M_main);
    e["M_other_rule_own_packing"] = Json::or_null(M_own);
    e["pressure_other_rule"] = Json::or_null(P_own);
    e["ratio_own_packing"] = Json::or_null(M_own / M_main);
    list.push(e);
  }
  rule["by_pressure"] = list;
  rule["what_changes"] =
      "the rule sets k_t, gamma_n, gamma_t and mu of unlike (stiff-soft) contacts; E* mixes "
      "as 1/E* = sum (1 - nu^2)/E under both; like pairs keep their own values. "
      "'same_packing' re-probes the packing prepared with the default rule (probing sees k_t "
      "only, sliding being off); 'own_packing' prepares and probes with the other rule (its "
      "smaller unlike friction also changes the packing)";
  return rule;
}

// The choices the run made where the source leaves them open (summary.json).
Json choices_json(const Setup& u) {
  Json ch = Json::object();
  Json mats = Json::object();
  for (const MixtureMaterial& m : u.mats.materials) {
    Json j = Json::object();
    j["modulus_reading"] =
        m.modulus_key == "shear_modulus"
            ? "the source's moduli column read as the shear modulus "
              "(default of docs/model_mixtures_and_waves.md §5): E = 2 G (1 + nu)"
            : "the source's moduli column read as Young's modulus";
    j["young_modulus_MPa"] = m.young;
    mats[m.name] = j;
  }
  ch["materials"] = mats;
  ch["E_star_MPa"] = Json::object();
  {
    Json& es = ch["E_star_MPa"];
    const std::string a = u.mats.materials[u.stiff].name, b = u.mats.materials[u.soft].name;
    es[a + "-" + a] = u.mats.effective_young(u.stiff, u.stiff);
    es[a + "-" + b] = u.mats.effective_young(u.stiff, u.soft);
    es[b + "-" + b] = u.mats.effective_young(u.soft, u.soft);
  }
  if (u.from)  // only then, so that the summaries of generated packings stay as they were
    ch["start"] =
        "the packing file of particles.from (its particles, box and species through "
        "particles.from_materials, at the velocities it holds), not a generated gas";
  ch["pair_rule"] = u.mats.pair_rule;
  // Only where the scene takes Mindlin's: a summary without it took the constant law (and
  // the constant law's summaries, every committed reference, stay as they were).
  if (u.mats.tangential_law != "constant")
    ch["tangential_law"] =
        "Mindlin: k_t = 8 G* sqrt(R delta), 1/G* = (2 - nu_i)/G_i + (2 - nu_j)/G_j";
  ch["pair_rule_scope"] =
      "k_t, gamma_n, gamma_t and mu of unlike species: harmonic 2pq/(p + q), product_over_sum "
      "pq/(p + q); like pairs keep their own values; Hertz E* always from 1/E* = sum "
      "(1 - nu^2)/E with R = a_i a_j/(a_i + a_j)";
  ch["normal_damping"] =
      "gamma sqrt(d delta) d(delta)/dt with d = a_i + a_j, as 2 gamma sqrt(R delta) "
      "d(delta)/dt (exact for equal spheres); gamma in ug/(mm us) = kg/(m s)";
  ch["bulk_density"] =
      "rho = sum(particle density x particle volume) / box volume, measured per packing "
      "(the packing's own density, about phi times the solids' density: M = rho V_p^2 "
      "then matches the quasi-static M; rho_solid is reported beside it)";
  ch["Vp"] = "sqrt(M / rho_bulk) with M from uniaxial probing, in m/s";
  ch["probing"] =
      "each mode (isotropic, pure shear in xy, uniaxial along x) restarts from the saved "
      "state, against a reference run without strain of the same length; sliding switched "
      "off (mu = inf) unless probe.keep_friction; strain and relaxation lengths in crossing "
      "times L sqrt(rho/K_affine) of the configuration";
  ch["configurations"] =
      u.unload_from > 0
          ? "picked at target pressures on the unloading branch of one sample per mixture: gas "
            "compressed to jamming and on to preparation.unload_from, settled there by the "
            "isotropic pressure servo (pressure_servo.hpp), then taken down by it through the "
            "decreasing targets until |P/P_target - 1| < tolerance and E_kin/E_pot < ekin_ratio"
          : "picked at target pressures on the loading branch of one sample per mixture: gas "
            "compressed to jamming, then the isotropic pressure servo (pressure_servo.hpp) until "
            "|P/P_target - 1| < tolerance and E_kin/E_pot < ekin_ratio";
  ch["fit"] =
      "least squares of log M against log P over the probed configurations of each mixture "
      "(default pair rule); stderr = s / sqrt(sum (log P - mean)^2)";
  return ch;
}

// The states the servo did not converge to, each with whether it was probed anyway.
Json unconverged_states(const std::map<std::string, std::vector<double>>& T) {
  const size_t rows = T.at("M").size();
  Json unconverged = Json::array();
  for (size_t i = 0; i < rows; ++i)
    if (T.at("servo_converged")[i] == 0) {
      Json e = Json::object();
      e["soft_fraction"] = T.at("soft_fraction")[i];
      e["pressure_target"] = T.at("pressure_target")[i];
      e["pressure"] = T.at("pressure")[i];
      e["ekin_over_epot"] = T.at("ekin_over_epot")[i];
      e["probed"] = T.at("probed")[i] > 0;
      unconverged.push(e);
    }
  return unconverged;
}

// The range of M / (K + 4G/3) over the probed configurations; null when none jammed.
Json m_ratio_range(const std::map<std::string, std::vector<double>>& T) {
  const size_t rows = T.at("M").size();
  double lo = INFINITY, hi = -INFINITY;
  for (size_t i = 0; i < rows; ++i)
    if (T.at("probed")[i] > 0)
      lo = -max_keep_nan(-lo, -T.at("M_over_M_KG")[i]),
      hi = max_keep_nan(hi, T.at("M_over_M_KG")[i]);
  return lo <= hi || std::isnan(lo) || std::isnan(hi) ? Json(std::vector<double>{lo, hi}) : Json();
}

// What this rank's mixtures returned: each one's part in mixture order (those a resumed run
// took from their checkpoints included; over several ranks none, rank 0 reads every part
// back), the parts this rank ran, and whether it stopped before its end
// (--stop-after-minutes: the checkpoints are its output so far).
struct MixturesRun {
  std::vector<ModuliOutputs> parts;
  std::vector<std::string> ran;
  bool stopped = false;
};

// Runs this rank's mixtures, each saved as a checkpoint part; those a resumed run finds done
// are taken from their parts.
MixturesRun run_mixtures(const Setup& u, const RunOptions& opts, const std::string& parts,
                         const std::string& fingerprint, const std::vector<std::string>& names) {
  const bool spread = ensemble::size() > 1;
  const StudyDeal deal = deal_study_units(parts, names, fingerprint, opts.resume);
  long total = 0, done = 0;
  for (size_t k = 0; k < u.variants.size(); ++k)
    if (deal.done[k] || deal.mine(k)) total += static_cast<long>(u.variants[k].pressures.size());
  Progress progress("mixtures", total, opts.progress);
  const auto start = std::chrono::steady_clock::now();
  MixturesRun run;
  for (size_t k = 0; k < u.variants.size(); ++k) {
    const Variant& v = u.variants[k];
    const std::string& name = names[k];
    if (deal.done[k]) {
      std::cerr << ensemble::prefix() << v.tag << ": taken from the checkpoint in " << parts
                << "\n";
      ModuliOutputs part;
      if (!spread && load_moduli_part(parts, name, fingerprint, part))
        run.parts.push_back(std::move(part));
      progress.update(done += static_cast<long>(v.pressures.size()));
      continue;
    }
    if (!deal.mine(k)) continue;
    const double minutes =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / 60;
    if (opts.stop_after_minutes > 0 && minutes >= opts.stop_after_minutes) {
      std::cerr << ensemble::prefix() << "stopped before variant " << k + 1 << " of "
                << u.variants.size() << " (--stop-after-minutes); continue with --resume\n";
      run.stopped = true;
      return run;
    }
    ModuliOutputs part = variant_part(v, run_variant(u, v, progress, done));
    save_moduli_part(parts, name, fingerprint, part);
    run.ran.push_back(name);
    if (!spread) run.parts.push_back(std::move(part));
  }
  if (ensemble::root()) progress.finish();  // the other ranks wrote their parts
  return run;
}

// Writes the study from its table (every mixture's rows in order): results.h5 (the table and
// the power-law fits), then summary.json and the charts.
void write_study(const SceneFile& scene, const RunOptions& opts, const Setup& u,
                 const ModuliOutputs& out) {
  const auto& T = out.table;
  const PowerLawFits fits = power_law_fits(u, T);
  const Json rule = u.check_pressures.empty() ? Json::object() : pair_rule_check(u, T);
  std::vector<std::string> table_units, fit_units;  // all of them before anything is written
  for (const auto& [k, v] : T) table_units.push_back(table_unit(k));
  for (const auto& [k, v] : fits.columns) fit_units.push_back(fit_unit(k));
  SceneOutput output(scene, opts, "mixture_moduli");
  H5Writer& h5 = output.h5();
  size_t col = 0;
  for (const auto& [k, v] : T) write_quantity(h5, "/table/" + k, v, table_units[col++]);
  col = 0;
  for (const auto& [k, v] : fits.columns) write_quantity(h5, "/fits/" + k, v, fit_units[col++]);

  Json& summary = output.summary();
  summary["choices"] = choices_json(u);
  summary["table"] = out.rows;
  summary["fits"] = fits.json;
  if (!u.check_pressures.empty()) summary["pair_rule_check"] = rule;
  summary["unconverged_states"] = unconverged_states(T);
  summary["M_over_K_plus_4G_3_range"] = m_ratio_range(T);
  output.finish({"table"});
}

}  // namespace

void check_mixture_moduli(const SceneFile& scene) { read_setup(scene); }

void run_mixture_moduli(const SceneFile& scene, const RunOptions& opts) {
  const Setup u = read_setup(scene);
  require_checkpoint_to_resume(opts, study_checkpoints(opts.out_dir));
  check_first_system(scene, opts, [&] {  // each mixture's gas, as compress_gas builds it
    for (const Variant& v : u.variants) {
      PeriodicBox box;
      const HostParticles host = start_of(u, v.soft_fraction, box);
      System(Particles<Exec>::from_host(host), box, u.mats.model(v.rule), gas_params(u, host));
    }
  });
  if (!begin_outputs(opts)) return;
  // Finished variants are checkpointed in variants/; summary.json and results.h5 appear only
  // when every variant is done, so an interrupted run leaves nothing that looks finished.
  const std::string parts = open_study_checkpoints(opts.out_dir, opts.resume);
  const std::string fingerprint = moduli_parameters_fingerprint(scene.used());
  if (ensemble::root())
    for (const char* f : {"/summary.json", "/results.h5"})
      std::filesystem::remove(opts.out_dir + f);  // never beside checkpoints of a newer run

  // Over several ranks each runs its share of the mixtures and rank 0 reads every part back
  // in mixture order; one rank runs them all, in order, as parts of a single process.
  std::vector<std::string> names;
  for (size_t k = 0; k < u.variants.size(); ++k)
    names.push_back("variant_" + std::to_string(k) + "_" + u.variants[k].tag);
  MixturesRun run = run_mixtures(u, opts, parts, fingerprint, names);
  ModuliOutputs out;
  if (ensemble::size() > 1)
    run.stopped = gather_study_units(parts, names, run.ran, {}, fingerprint, run.stopped, out);
  else
    for (const ModuliOutputs& part : run.parts) out.append(part);
  if (!ensemble::root() || run.stopped) return;  // the checkpoints in variants/ are the output
  write_study(scene, opts, u, out);
  remove_study_checkpoints(parts);  // everything is in results.h5 and summary.json now
}

}  // namespace granular
