// Reading and checking an elastic_moduli scene file.
#include "scenarios/moduli/moduli_setup.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>

#include "core/run/error.hpp"
#include "scenarios/common/packing_file.hpp"

namespace granular::moduli_study {

namespace {
// start.from as another tool's packing, or null for a saved configuration: a `.h5` file is a
// saved configuration (springs and all) unless start.from_group names a state group in it;
// an H5MD series (`.h5md`, its last frame) or a LAMMPS data file (any other name) is a
// packing. H5MD frames and state groups hold no density: start.density gives it.
std::shared_ptr<const ConfigState> read_start_packing(const SceneFile& scene,
                                                      const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  const std::string group = scene.text("start.from_group", "");
  if (ext == ".h5" && group.empty()) return nullptr;
  PeriodicBox box;
  HostParticles h = read_scene_packing(scene, "start.from", path, "start.density",
                                       group.empty() ? "/final_state" : group, box);
  for (double d : h.density)
    scene.require(d > 0 && std::isfinite(d), "start.from",
                  "holds a particle of non-positive density");
  return std::make_shared<const ConfigState>(config_from_packing(std::move(h), box));
}

// The time step, skin, damping and the run's limits.
void read_run(const SceneFile& scene, Setup& s) {
  s.params.dt = scene.real("run.dt");
  scene.require(s.params.dt > 0, "run.dt", "must be positive");
  s.params.dt_key = "run.dt";
  s.params.skin = scene.real("run.skin");
  s.params.damping.translational = scene.real("damping.background", 0.0);
  s.params.damping.rotational = scene.real("damping.rotational", 0.0);
  s.params.rattler_threshold = scene.small_integer("run.rattler_threshold", 3);
  s.params.max_overlap = scene.real("run.max_overlap", 0.5);
  s.stop_after_variants = scene.integer("run.stop_after_variants", 0);
  s.stop_after_stages = scene.integer("run.stop_after_stages", 0);
  scene.require(s.stop_after_variants >= 0, "run.stop_after_variants", "must not be negative");
  scene.require(s.stop_after_stages >= 0, "run.stop_after_stages", "must not be negative");
  // A negative skin lists no pair (every particle a rattler, no moduli): refused.
  scene.require(s.params.skin > 0 && std::isfinite(s.params.skin), "run.skin",
                "must be positive and finite");
}

// How a state is relaxed and which friction the preparation uses.
void read_relaxation(const SceneFile& scene, Setup& s) {
  s.relax_ratio = scene.real("preparation.relax_ratio", 1e-8);
  s.relax_max = scene.integer("preparation.relax_max_steps", 200000);
  // Read only when present, so that studies checkpointed before the key existed resume.
  if (scene.has("preparation.friction_from")) {
    const std::string from = scene.text("preparation.friction_from");
    scene.require(from == "start" || from == "phi_0", "preparation.friction_from",
                  "must be \"start\" (the gas too, the default) or \"phi_0\"");
    s.friction_from_phi0 = from == "phi_0";
  }
  s.jamming_p_max =
      scene.real("preparation.jamming_fit_pressure_max", s.contact.normal == "hertz" ? 0.0 : 1e-3);
  scene.require(s.jamming_p_max >= 0, "preparation.jamming_fit_pressure_max",
                "must not be negative (0: no fit)");
}

// The probes: amplitude, steps, the sweeps over k_t, amplitudes and pre-strains.
void read_probe(const SceneFile& scene, Setup& s) {
  s.amplitude = scene.real("probe.amplitude", 3e-6);
  s.strain_steps = scene.integer("probe.strain_steps", 2000);
  s.probe_relax = scene.integer("probe.relax_steps", 2000);
  s.probe_inertial = scene.real("probe.inertial_number", 0.0);
  s.max_strain_steps = scene.integer("probe.max_strain_steps", 200000);
  // The probe's step count is clamped to [20, max_strain_steps]: a bound below 20 would
  // invert the clamp (undefined behaviour, K* inf and G* -inf).
  scene.require(s.max_strain_steps >= 20, "probe.max_strain_steps", "must be at least 20");
  s.keep_friction = scene.flag("probe.keep_friction", false);
  s.halving = scene.flag("probe.halving_check", false);
  s.orientations = scene.small_integer("probe.orientations", 1);
  scene.require(s.orientations == 1 || s.orientations == 3, "probe.orientations",
                "must be 1 (shear in xy, uniaxial along x) or 3 (all planes and axes, averaged)");
  s.kt_ratios = scene.reals("probe.kt_over_kn", {});
  s.amplitudes = scene.reals("probe.amplitudes", {});
  s.sweep_same_steps = scene.flag("probe.amplitudes_same_steps", false);
  s.prestrains = scene.reals("probe.prestrains", {});
  s.prestrain_relax_ratio = scene.real("probe.prestrain_relax_ratio", 1e-10);
  scene.require(s.prestrain_relax_ratio > 0, "probe.prestrain_relax_ratio", "must be positive");
  scene.require(s.amplitude > 0 && s.amplitude < 1e-2, "probe.amplitude", "must be in (0, 1e-2)");
  scene.require(s.strain_steps > 0 && s.probe_relax >= 0, "probe.strain_steps",
                "and probe.relax_steps must be positive");
  scene.require(s.probe_relax <= 100000000, "probe.relax_steps", "must be at most 1e8");
  scene.require(s.relax_max > 0 && s.relax_max <= 100000000, "preparation.relax_max_steps",
                "must lie in [1, 1e8]");
  scene.require(s.probe_inertial >= 0 && s.probe_inertial < 1e-2, "probe.inertial_number",
                "must be in [0, 1e-2) (quasi-static probing: 1e-4 ... 1e-6)");
  for (double a : s.amplitudes)
    scene.require(a > 0 && a <= 0.05, "probe.amplitudes", "must lie in (0, 0.05]");
  for (double r : s.kt_ratios) scene.require(r >= 0, "probe.kt_over_kn", "must not be negative");
  for (double e : s.prestrains)
    scene.require(e > s.amplitude && e <= 0.05, "probe.prestrains",
                  "must lie in (probe.amplitude, 0.05]: the reversal starts with one amplitude");
  if (!s.kt_ratios.empty())
    scene.require(s.contact.tangential == "coulomb" && s.contact.coulomb.law == 0 &&
                      s.contact.normal != "hertz",
                  "probe.kt_over_kn",
                  "needs a linear or hysteretic normal law with a constant tangential spring");
}

// The gas and its compression to the target volume fractions.
void read_gas_preparation(const SceneFile& scene, Setup& s) {
  GasSpec& g = s.gas;
  const long count = scene.integer("particles.count", 0);
  scene.require(count >= 0 && count <= std::numeric_limits<int>::max(), "particles.count",
                "must be in [2, 2^31)");
  g.count = static_cast<int>(count);
  g.diameter_min = scene.real("particles.diameter_min");
  g.diameter_max = scene.real("particles.diameter_max");
  g.density = scene.real("particles.density");
  g.seed = static_cast<std::uint64_t>(scene.integer("particles.seed", 1));
  g.speed = scene.real("particles.initial_speed", 0.0);
  g.phi = scene.real("preparation.phi_gas", 0.3);
  s.phi0 = scene.real("preparation.phi_0", 0.5);
  s.phi_max = scene.real("preparation.phi_max");
  s.rate = scene.real("preparation.volumetric_strain_rate");
  s.prep_inertial = scene.real("preparation.inertial_number", 0.0);
  s.min_rate = scene.real("preparation.min_volumetric_strain_rate", s.rate / 20);
  // The gas below phi_0 has no contact network to keep quasi-static (its pressure is tiny,
  // so an inertial-number rule would crawl at the minimum rate) and is relaxed to zero
  // pressure afterwards: it is compressed at this constant rate.
  s.gas_rate = scene.real("preparation.gas_strain_rate", s.rate);
  scene.require(s.gas_rate > 0, "preparation.gas_strain_rate", "must be positive");
  const std::string branch = scene.text("preparation.branch", "unloading");
  scene.require(branch == "unloading" || branch == "loading", "preparation.branch",
                "must be \"unloading\" (decompression from phi_max) or \"loading\"");
  s.loading_branch = branch == "loading";
  s.targets = scene.reals("preparation.targets");
  scene.require_distinct("preparation.targets", s.targets);
  check_gas(scene, g, "preparation.phi_gas");
  scene.require(s.phi0 > g.phi && s.phi_max > s.phi0 && s.phi_max < 1, "preparation.phi_max",
                "must satisfy phi_gas < phi_0 < phi_max < 1");
  for (double t : s.targets)
    scene.require(t > s.phi0 && t < s.phi_max, "preparation.targets",
                  "must lie between phi_0 and phi_max");
  scene.require(s.rate > 0, "preparation.volumetric_strain_rate", "must be positive");
  scene.require(s.min_rate > 0 && s.min_rate <= s.rate, "preparation.min_volumetric_strain_rate",
                "must be in (0, preparation.volumetric_strain_rate]");
}

// Preparation variants: sizes x seeds x friction coefficients x adhesive stiffnesses.
void read_variants(const SceneFile& scene, Setup& s) {
  const GasSpec& g = s.gas;
  std::vector<double> counts = scene.reals("ensemble.counts", {});
  std::vector<double> seeds = scene.reals("ensemble.seeds", {});
  const std::vector<double> mus = scene.reals("preparation.mu", {});
  scene.require_distinct("preparation.mu", mus);
  if (counts.empty()) counts.push_back(g.count);
  if (seeds.empty()) seeds.push_back(static_cast<double>(g.seed));
  for (double c : counts) {
    scene.require(c >= 2 && c <= std::numeric_limits<int>::max(), "particles.count",
                  "(or ensemble.counts) must be in [2, 2^31)");
    scene.require_memory("particles.count", c * kDemBytesPerParticle);
  }
  for (double m : mus) scene.require(m >= 0, "preparation.mu", "must not be negative");
  if (!mus.empty())
    scene.require(s.contact.tangential == "coulomb", "preparation.mu",
                  "needs contact.tangential = \"coulomb\"");
  // Cohesion list: one preparation per k_c of the hysteretic law (K and G against k_c, the
  // preparation path with and without cohesion).
  const std::vector<double> kcs = scene.reals("preparation.kc", {});
  for (double k : kcs) scene.require(k >= 0, "preparation.kc", "must not be negative");
  if (!kcs.empty())
    scene.require(s.contact.normal == "hysteretic", "preparation.kc",
                  "needs contact.normal = \"hysteretic\" (k_c is its adhesive stiffness)");
  // Time step per k_c: the adhesive branch of a large k_c is the stiffest spring, and only the
  // variants that have it need the step it forces on them.
  const std::vector<double> dts = scene.reals("preparation.dt", {});
  if (!dts.empty())
    scene.require(dts.size() == kcs.size(), "preparation.dt",
                  "needs one time step per entry of preparation.kc");
  for (double d : dts) scene.require(d > 0, "preparation.dt", "must be positive");
  const std::vector<double> mu_list = mus.empty() ? std::vector<double>{kNaN} : mus;
  const std::vector<double> kc_list = kcs.empty() ? std::vector<double>{kNaN} : kcs;
  for (double c : counts)
    for (double sd : seeds)
      for (double mu : mu_list)
        for (size_t ik = 0; ik < kc_list.size(); ++ik) {
          const double kc = kc_list[ik];
          PrepVariant v;
          v.count = static_cast<int>(c), v.seed = static_cast<std::uint64_t>(sd), v.mu = mu;
          v.kc = kc;
          if (!dts.empty()) v.dt = dts[ik];
          char buf[128] = "";
          if (counts.size() > 1 || seeds.size() > 1)
            std::snprintf(buf, sizeof buf, "N%d_seed%d", v.count, static_cast<int>(sd));
          if (mus.size() > 1)
            std::snprintf(buf + std::strlen(buf), sizeof buf - std::strlen(buf), "%smu%g",
                          buf[0] ? "_" : "", mu);
          if (kcs.size() > 1)
            std::snprintf(buf + std::strlen(buf), sizeof buf - std::strlen(buf), "%skc%g",
                          buf[0] ? "_" : "", kc);
          v.tag = buf;
          s.variants.push_back(v);
        }
}

}  // namespace

Setup read_setup(const SceneFile& scene) {
  Setup s;
  s.start_from = scene.optional_input_path("start.from");
  if (!s.start_from.empty()) s.start_packing = read_start_packing(scene, s.start_from);
  s.contact = ContactConfig::read(scene);
  read_run(scene, s);
  read_relaxation(scene, s);
  read_probe(scene, s);
  if (!s.start_from.empty()) {
    s.variants.push_back({});
    scene.reject_unknown_keys();
    return s;
  }
  read_gas_preparation(scene, s);
  read_variants(scene, s);
  scene.reject_unknown_keys();
  return s;
}

Setup for_variant(const Setup& s, const PrepVariant& v) {
  Setup r = s;
  if (std::isnan(v.dt) || v.dt == s.params.dt) return r;
  const double scale = s.params.dt / v.dt;
  auto steps = [&](long n) { return std::max(1L, std::lround(static_cast<double>(n) * scale)); };
  r.params.dt = v.dt;
  r.params.dt_key = "preparation.dt";
  r.strain_steps = steps(s.strain_steps);
  r.probe_relax = s.probe_relax > 0 ? steps(s.probe_relax) : 0;
  r.relax_max = steps(s.relax_max);
  r.max_strain_steps = steps(s.max_strain_steps);
  return r;
}

}  // namespace granular::moduli_study
