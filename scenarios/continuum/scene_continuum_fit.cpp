// Scene `continuum_fit`: the continuum law of docs/model_continuum.md fitted to the engine's own
// elastic-moduli studies and checked against DEM paths, in one run:
//   parse -> spec example (regression of the source's isotropic path) -> fit each study and
//   preparation friction, with the isotropic validation on the preparation path (constants.txt
//   written once the fits are made) -> a deformation history through one fitted law -> DEM
//   pure shear against the law -> write (results.h5, summary.json, charts).
// Each stage returns its results as data (ContinuumResults); the write_ functions write them.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>
#include <sstream>

#include "core/continuum/deformation_paths.hpp"
#include "core/io/dataset_units.hpp"
#include "core/io/output.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/common/scene_output.hpp"
#include "scenarios/continuum/continuum_fitting.hpp"
#include "scenarios/continuum/continuum_shear_dem.hpp"
#include "scenarios/scene_registry.hpp"

namespace granular {

namespace {

struct DataSet {
  std::string name, study;
};

struct Setup {
  VolumeFractionUpdate update = VolumeFractionUpdate::mass_conservation;
  double step = 0;  // stretch increment of the material-point paths
  double z_min = 0;
  std::vector<DataSet> data;
  double example_step = 0, example_nu_end = 0;
  // A deformation-gradient history (file of time and F rows) driven through one fitted law.
  std::string history_file, history_data;
  DeformationTable history_table;  // read with the keys, so a bad table fails before the fits
  double history_fit_mu = 0, history_nu_start = 0;
  int history_substeps = 1;
  bool shear = false;
  std::string shear_data;  // the fit (data set and preparation friction) the shear run checks
  double shear_fit_mu = 0;
  DemShearSpec dem;
};

// The DEM pure-shear run of [shear], read and checked.
DemShearSpec read_dem_shear(const SceneFile& scene) {
  DemShearSpec d;
  d.gas.count = scene.small_integer("shear.count");
  d.gas.diameter_min = scene.real("shear.diameter_min");
  d.gas.diameter_max = scene.real("shear.diameter_max");
  d.gas.density = scene.real("shear.density");
  d.gas.seed = static_cast<std::uint64_t>(scene.integer("shear.seed"));
  d.gas.speed = scene.real("shear.initial_speed", 0.0);
  d.gas.phi = scene.real("shear.phi_gas");
  d.kn = scene.real("shear.kn"), d.gamma_n = scene.real("shear.gamma_n");
  d.kt = scene.real("shear.kt"), d.gamma_t = scene.real("shear.gamma_t");
  d.mu = scene.real("shear.mu");
  d.damping_background = scene.real("shear.damping_background");
  d.damping_rotational = scene.real("shear.damping_rotational");
  d.dt = scene.real("shear.dt"), d.skin = scene.real("shear.skin");
  scene.require(d.dt > 0, "shear.dt", "must be positive");
  scene.require(d.skin > 0, "shear.skin", "must be positive");
  d.max_overlap = scene.real("shear.max_overlap", 0.5);
  d.phi = scene.real("shear.phi");
  d.volumetric_strain_rate = scene.real("shear.volumetric_strain_rate");
  d.relax_ratio = scene.real("shear.relax_ratio", 1e-8);
  d.relax_max_steps = scene.integer("shear.relax_max_steps");
  d.strain = scene.real("shear.strain");
  d.strain_rate = scene.real("shear.strain_rate");
  d.samples = scene.small_integer("shear.samples");
  scene.require(d.gas.count >= 10, "shear.count", "must be at least 10");
  // The gas rule every scene uses (sizes, size ratio, a box the doubles can measure): a
  // check of its own here let diameter_max = 1e308 through to a segmentation fault.
  check_gas(scene, d.gas, "shear.phi_gas", "shear");
  scene.require(d.phi > d.gas.phi && d.phi < 0.9, "shear.phi", "must lie in (shear.phi_gas, 0.9)");
  scene.require(d.strain > 0 && d.strain < 0.2, "shear.strain", "must lie in (0, 0.2)");
  scene.require(d.strain_rate > 0, "shear.strain_rate", "must be positive");
  scene.require(d.volumetric_strain_rate > 0, "shear.volumetric_strain_rate", "must be positive");
  scene.require(d.samples >= 2, "shear.samples", "must be at least 2");
  scene.require(d.mu >= 0, "shear.mu", "must not be negative");
  return d;
}

Setup read_setup(const SceneFile& scene) {
  Setup s;
  s.update =
      scene.choice("law.volume_fraction_update", "mass_conservation", volume_fraction_update_from);
  s.step = scene.real("law.step");
  scene.require(s.step > 0 && s.step < 0.01, "law.step", "must lie in (0, 0.01)");
  s.z_min = scene.real("fit.z_min", 4.0);
  scene.require(s.z_min >= 0 && s.z_min < 12, "fit.z_min",
                "must lie in [0, 12): a contact number the packings reach");
  for (const std::string& name : scene.tables("data"))
    s.data.push_back({name, scene.input_path("data." + name + ".study", true)});
  scene.require(!s.data.empty(), "data", "needs at least one [data.<name>] table with a study");
  s.example_step = scene.real("example.step", -1e-4);
  s.example_nu_end = scene.real("example.nu_end", 0.82);
  scene.require(s.example_step < 0, "example.step", "must be negative (compression)");
  scene.require(s.example_nu_end > 0 && s.example_nu_end < 1, "example.nu_end",
                "must lie in (0, 1)");
  s.history_file = scene.optional_input_path("history.file");
  if (!s.history_file.empty()) {
    s.history_data = scene.text("history.data");
    s.history_fit_mu = scene.real("history.fit_mu");
    s.history_nu_start = scene.real("history.nu_start");
    s.history_substeps = scene.small_integer("history.substeps", 1);
    scene.require(s.history_nu_start > 0 && s.history_nu_start < 1, "history.nu_start",
                  "must lie in (0, 1)");
    scene.require(s.history_substeps >= 1, "history.substeps", "must be at least 1");
    try {
      s.history_table = read_deformation_table(s.history_file);
    } catch (const InputError& e) {
      scene.require(false, "history.file", e.what());
    }
  }
  s.shear = scene.flag("shear.run");
  if (s.shear) {
    s.shear_data = scene.text("shear.data");
    s.shear_fit_mu = scene.real("shear.fit_mu");
    s.dem = read_dem_shear(scene);
  }
  scene.reject_unknown_keys();
  return s;
}

std::string key_of(const ModuliData& d, const std::string& set) {
  std::ostringstream k;
  k << set << "_mu" << d.mu;
  return k.str();
}

Json branch_json(const BranchError& b) {
  Json j = Json::object();
  j["points"] = static_cast<int>(b.phi.size());
  j["rms_error_MPa"] = b.rms;
  j["max_abs_error_MPa"] = b.max_abs;
  j["largest_dem_pressure_MPa"] = b.p_scale;
  j["rms_error_relative_to_largest_pressure"] = b.p_scale > 0 ? b.rms / b.p_scale : 0.0;
  return j;
}

Json fit_json(const LeastSquaresFit& f, const char* what) {
  Json j = Json::object();
  j["what"] = what;
  j["points"] = f.points;
  j["degrees_of_freedom"] = f.dof;
  j["rms_residual"] = f.rms;
  j["converged"] = f.converged;
  j["iterations"] = f.iterations;
  return j;
}

// Relative error per configuration, for the summary's "where it fails" lines.
Json per_point_relative(const BranchError& b) {
  Json a = Json::array();
  for (size_t i = 0; i < b.phi.size(); ++i) {
    Json r = Json::object();
    r["phi"] = b.phi[i];
    r["p_dem_MPa"] = b.p_dem[i];
    r["p_law_MPa"] = b.p_law[i];
    r["relative_error"] = b.p_dem[i] > 0 ? (b.p_law[i] - b.p_dem[i]) / b.p_dem[i] : 0.0;
    a.push(r);
  }
  return a;
}

// 1. The source's example: isotropic compression from nu0 to nu_end, one path per update.
struct ExamplePath {
  VolumeFractionUpdate update = VolumeFractionUpdate::mass_conservation;
  PathRecord record;
  double nu_end = 0, J_end = 0, pressure_end = 0;  // Cauchy pressure
};

std::vector<ExamplePath> spec_example(const Setup& s) {
  std::vector<ExamplePath> paths;
  const ContinuumConstants c = ContinuumConstants::spec_example();
  for (VolumeFractionUpdate u :
       {VolumeFractionUpdate::mass_conservation, VolumeFractionUpdate::exponential}) {
    MaterialPoint p(c, c.nu0, u);
    ExamplePath e;
    e.update = u;
    e.record = drive_to_volume_fraction(p, step_increment(PathKind::isotropic, s.example_step),
                                        s.example_nu_end);
    e.nu_end = p.nu(), e.J_end = p.J(), e.pressure_end = p.pressure();
    paths.push_back(std::move(e));
  }
  return paths;
}

// The fitted law's curves over the data's range (nu0 to the preparation's peak), for the
// charts.
struct LawCurves {
  std::vector<double> nu, C, Fv, K, G;
};

// 2. One fit: the data of one study's preparation friction, the fitted law, its own tangent
// against K(nu), G(nu) and the isotropic validation.
struct StudyFit {
  DataSet set;
  ModuliData data;
  std::string key;  // data set and preparation friction
  ContinuumFit fit;
  IsotropicValidation validation;
  double tangent_dK = 0, tangent_dG = 0;  // largest relative differences at the data's phi
  LawCurves curves;
};

// The update's own tangent at the data's volume fractions against K(nu), G(nu): what an FE
// code integrating this law sees in one step.
void tangent_check(StudyFit& r, VolumeFractionUpdate update) {
  for (double phi : r.data.phi) {
    const ContinuumModuli m = continuum_moduli(r.fit.law, phi);
    const TangentModuli t = numerical_tangent(r.fit.law, phi, update);
    if (m.K > 0) r.tangent_dK = std::max(r.tangent_dK, std::abs(t.K - m.K) / m.K);
    if (m.G > 0) r.tangent_dG = std::max(r.tangent_dG, std::abs(t.G - m.G) / m.G);
  }
}

LawCurves law_curves(const ContinuumFit& f, const ModuliData& d) {
  LawCurves c;
  for (int i = 0; i <= 400; ++i) {
    const double x = f.law.nu0 + (d.prep_phi[d.peak] - f.law.nu0) * i / 400.0;
    const ContinuumModuli m = continuum_moduli(f.law, x);
    c.nu.push_back(x), c.C.push_back(m.C), c.Fv.push_back(m.Fv), c.K.push_back(m.K);
    c.G.push_back(m.G);
  }
  return c;
}

// Fits and the isotropic validation, per study and preparation friction, in the order the
// studies are listed.
std::vector<StudyFit> fit_studies(const SceneFile& scene, const Setup& s) {
  std::vector<StudyFit> fits;
  double kept = 0;  // bytes of the law cycles of the fits before (kept until the end)
  for (const DataSet& set : s.data) {
    for (ModuliData& d : read_moduli_study(set.study, set.name)) {
      StudyFit r;
      r.set = set, r.key = key_of(d, set.name);
      std::cerr << "fitting " << d.name << " (" << set.study << ")\n";
      r.fit = fit_continuum_law(d, s.z_min);
      // The validation path keeps 15 doubles per law step (twice that while growing), and
      // the law cycles of the fits before are kept until the run is written: refused naming
      // the key rather than allocating gigabytes for a tiny step.
      if (!d.prep_phi.empty() && r.fit.law.nu0 > 0) {
        const double lo = *std::min_element(d.prep_phi.begin(), d.prep_phi.end()),
                     hi = *std::max_element(d.prep_phi.begin(), d.prep_phi.end());
        const double span = std::abs(std::log(hi / r.fit.law.nu0)) + std::abs(std::log(hi / lo));
        scene.require_memory("law.step", kept + (span / (3 * s.step) + 2) * 15 * 8 * 2);
      }
      r.validation = validate_isotropic(d, r.fit.law, s.update, s.step);
      kept += 8.0 * (r.validation.law_phi.size() + r.validation.law_p.size());
      r.data = std::move(d);
      tangent_check(r, s.update);
      r.curves = law_curves(r.fit, r.data);
      fits.push_back(std::move(r));
    }
  }
  return fits;
}

// The fit of data set `data` at preparation friction `mu`, as the table [table] names it
// (keys <table>.data and <table>.fit_mu), the last made under that key; an input error when
// no such fit was made.
const StudyFit& fit_named(const SceneFile& scene, const std::vector<StudyFit>& fits,
                          const std::string& table, const std::string& data, double mu) {
  std::ostringstream k;
  k << data << "_mu" << mu;
  const auto it =
      std::find_if(fits.rbegin(), fits.rend(), [&](const StudyFit& f) { return f.key == k.str(); });
  if (it == fits.rend())
    throw InputError(scene.path() + ": " + table + ".data / " + table +
                     ".fit_mu name no fitted data set (" + k.str() + ")");
  return *it;
}

// 3. A tabulated deformation history through one fitted law.
struct HistoryRun {
  std::string fit;  // its key
  std::vector<double> time;
  PathRecord record;
  double nu_end = 0, pressure_end = 0, von_mises_end = 0;
};

HistoryRun drive_history(const SceneFile& scene, const Setup& s,
                         const std::vector<StudyFit>& fits) {
  const StudyFit& f = fit_named(scene, fits, "history", s.history_data, s.history_fit_mu);
  const DeformationTable& table = s.history_table;
  MaterialPoint p(f.fit.law, s.history_nu_start, s.update);
  HistoryRun h;
  h.fit = f.key;
  h.record = drive_table(p, table, s.history_substeps);
  h.time = {table.time.front()};
  for (size_t row = 1; row < table.time.size(); ++row)
    for (int q = 1; q <= s.history_substeps; ++q)
      h.time.push_back(table.time[row - 1] +
                       (table.time[row] - table.time[row - 1]) * q / s.history_substeps);
  h.nu_end = p.nu(), h.pressure_end = p.pressure(), h.von_mises_end = p.deviatoric();
  return h;
}

// 4. DEM pure shear against the law fitted to the matching preparation: the law starts from
// the DEM's own stress and volume fraction and follows the box's F (10 sub-steps per
// sample); stresses compared as mean stress and the xx - yy deviator.
struct ShearRun {
  std::string fit;  // the key of the law compared
  DemShearPath dem;
  std::vector<double> strain, p_dem, p_law, d_dem, d_law;  // axial true strain, MPa
  double mean_stress_rms = 0, deviator_rms = 0, deviator_max = 0;
  double fail_strain = NAN;  // where the deviator first misses the DEM's by 10 %; NaN: never
};

void follow_dem(ShearRun& r, const ContinuumConstants& law, VolumeFractionUpdate update) {
  const DemShearPath& dem = r.dem;
  Mat3 tau0 = Mat3::Zero();
  tau0(0, 0) = -dem.sxx[0], tau0(1, 1) = -dem.syy[0], tau0(2, 2) = -dem.szz[0];
  tau0(0, 1) = tau0(1, 0) = -dem.sxy[0], tau0(0, 2) = tau0(2, 0) = -dem.sxz[0];
  tau0(1, 2) = tau0(2, 1) = -dem.syz[0];
  MaterialPoint p(law, dem.phi, update, tau0);
  std::vector<double> err_p, err_d;
  const int sub = 10;
  double rms_p = 0, rms_d = 0;
  for (size_t i = 0; i < dem.sxx.size(); ++i) {
    if (i > 0)
      for (int q = 1; q <= sub; ++q) {
        const double w = static_cast<double>(q) / sub;
        Mat3 F = Mat3::Zero();
        F(0, 0) = (1 - w) * dem.stretch_x[i - 1] + w * dem.stretch_x[i];
        F(1, 1) = (1 - w) * dem.stretch_y[i - 1] + w * dem.stretch_y[i];
        F(2, 2) = (1 - w) * dem.stretch_z[i - 1] + w * dem.stretch_z[i];
        p.step_to(F);
      }
    const Mat3 sig = -p.cauchy();  // compression positive, like the DEM
    r.strain.push_back(-std::log(dem.stretch_x[i]));
    r.p_dem.push_back(dem.pressure[i]), r.p_law.push_back(sig.trace() / 3);
    r.d_dem.push_back(dem.sxx[i] - dem.syy[i]), r.d_law.push_back(sig(0, 0) - sig(1, 1));
    err_p.push_back(r.p_law.back() - r.p_dem.back());
    err_d.push_back(r.d_law.back() - r.d_dem.back());
    rms_p += err_p.back() * err_p.back(), rms_d += err_d.back() * err_d.back();
    r.deviator_max = std::max(r.deviator_max, std::abs(err_d.back()));
    // First strain where the deviator misses the DEM's by more than 10 % of the DEM's.
    const double growth = r.d_dem.back() - r.d_dem.front();
    if (std::isnan(r.fail_strain) && i > 0 &&
        std::abs(err_d.back() - err_d.front()) > 0.1 * std::abs(growth))
      r.fail_strain = r.strain.back();
  }
  const double n = static_cast<double>(r.strain.size());
  r.mean_stress_rms = std::sqrt(rms_p / n), r.deviator_rms = std::sqrt(rms_d / n);
}

ShearRun validate_shear(const SceneFile& scene, const Setup& s, const std::vector<StudyFit>& fits) {
  const StudyFit& f = fit_named(scene, fits, "shear", s.shear_data, s.shear_fit_mu);
  std::cerr << "DEM pure shear (" << s.dem.gas.count << " particles, phi " << s.dem.phi << ")\n";
  ShearRun r;
  r.fit = f.key;
  r.dem = run_dem_pure_shear(s.dem);
  follow_dem(r, f.fit.law, s.update);
  return r;
}

// What the run found, in the order it is written.
struct ContinuumResults {
  std::vector<ExamplePath> example;
  std::vector<StudyFit> fits;
  std::optional<HistoryRun> history;
  std::optional<ShearRun> shear;
};

// constants.txt: every fit's constants, written as soon as the fits are made (before the
// history and the shear run, which may still be refused).
void write_constants(SceneOutput& output, const SceneFile& scene, const Setup& s,
                     const std::vector<StudyFit>& fits) {
  std::ostringstream txt;
  txt << "# Continuum-law constants (docs/model_continuum.md) fitted by the continuum_fit scene ("
      << scene.path() << ").\n"
      << "# K = K0 + K1 (F_v - F_v0), G = G0 + G1 (F_v - F_v0)^G2 in MPa (N/mm^2);\n"
      << "# C* = C0 + C1 (nu/nu0 - 1)^alpha (0 below nu0), F_v = C* g3 nu.\n"
      << "# Volume fraction update used in the validation: " << to_string(s.update)
      << ". Below nu0: K = G = 0 and no stress; for F_v < F_v0: G = G0.\n";
  for (const StudyFit& r : fits) {
    txt << "\n[" << r.data.name << "]  # study " << r.set.study << "\n";
    for (const FittedConstant& c : r.fit.constants) {
      char line[160];
      std::snprintf(line, sizeof line, "%-6s = %-14.8g # +- %.3g %s%s\n", c.name, c.value,
                    c.std_error, c.unit, c.at_bound ? " (at a bound of the fit)" : "");
      txt << line;
    }
  }
  write_text_file(output.path("constants.txt"), txt.str());
}

// The example's paths in /example/<update> and summary.json's spec_example.
void write_example(H5Writer& h5, Json& summary, const std::vector<ExamplePath>& paths) {
  Json& ex = summary["spec_example"];
  ex = Json::object();
  ex["constants_units"] = ContinuumConstants::spec_example().units;
  for (const ExamplePath& path : paths) {
    const PathRecord& r = path.record;
    const std::string g = std::string("/example/") + to_string(path.update);
    // The source prints K0, K1, G0, G1 without a unit (docs/model_continuum.md §6): the
    // example's pressure and K are numbers in that unprinted stress unit, labelled "1".
    write_quantity(h5, g + "/nu", r.nu, "1");
    write_quantity(h5, g + "/pressure", r.pressure, "1");
    write_quantity(h5, g + "/K", r.K, "1");
    Json& e = ex[to_string(path.update)];
    e = Json::object();
    e["steps"] = static_cast<long>(r.size() - 1);
    e["nu_end"] = path.nu_end;
    e["J_end"] = path.J_end;
    e["cauchy_pressure_end"] = path.pressure_end;
    e["kirchhoff_pressure_end"] = path.pressure_end * path.J_end;
  }
  ex["exponential_over_mass_conservation_pressure"] = paths[1].pressure_end / paths[0].pressure_end;
}

Json fit_quality_json(const ContinuumFit& f) {
  Json jr = Json::object();
  jr["coordination"] = fit_json(f.coordination, "C*(nu) against Z* of the unloading series");
  jr["coordination"]["note"] =
      "points are consecutive samples of one preparation, correlated in time: the standard "
      "errors assume independent residuals and are therefore lower bounds";
  jr["fabric"] = fit_json(f.fabric, "F_v = g3 C* nu against the table's fabric trace");
  jr["bulk"] = fit_json(f.bulk, "K = K0 + K1 (F_v - F_v0), MPa");
  jr["shear"] = fit_json(f.shear, "G = G0 + G1 (F_v - F_v0)^G2, MPa");
  return jr;
}

Json validation_json(const IsotropicValidation& v) {
  Json jv = Json::object();
  jv["path"] =
      "law compressed from nu0 (stress-free) to the series' largest phi, then decompressed; "
      "DEM: /preparation pressure of this friction (loading at the preparation rate, then "
      "unloading), and the relaxed configurations of /table";
  jv["loading"] = branch_json(v.loading);
  jv["unloading"] = branch_json(v.unloading);
  jv["configurations"] = branch_json(v.configurations);
  jv["configurations"]["per_configuration"] = per_point_relative(v.configurations);
  return jv;
}

// One fit's entry of summary.json.
Json fit_entry(const StudyFit& r) {
  const ModuliData& d = r.data;
  const ContinuumFit& f = r.fit;
  Json j = Json::object();
  j["key"] = r.key;
  j["data_set"] = d.name;
  j["study"] = r.set.study;
  j["preparation_friction"] = d.mu;
  j["data"] =
      "C*(nu): unloading branch of /preparation (variant of this friction, Z* >= fit.z_min, "
      "P > 0); g3, K, G: jammed rows of /table (unloading-branch configurations, probed "
      "with tangential springs and mu = infinity)";
  j["units"] = f.law.units;
  j["dimensionless_scale"] =
      "K* = K dbar / kn_mean; with a constant kn_mean (linear contacts) divide K0, K1, G0, "
      "G1 by kn/dbar";
  // A single scale exists only where every configuration has the same contact stiffness
  // (linear contacts); Hertz stiffnesses grow with the overlap.
  const auto [kn_lo, kn_hi] = std::minmax_element(d.kn_mean.begin(), d.kn_mean.end());
  if (*kn_hi - *kn_lo <= 1e-12 * *kn_hi)
    j["kn_over_dbar_MPa"] = d.kn_mean.front() / d.d_mean;
  else
    j["kn_over_dbar_MPa"] = "varies with phi (kn_mean of each configuration): no single scale";
  Json& jc = j["constants"];
  jc = Json::object();
  for (const FittedConstant& c : f.constants) {
    Json e = Json::object();
    e["value"] = c.value;
    e["std_error"] = c.std_error;
    e["unit"] = c.unit;
    if (c.at_bound) e["at_bound"] = true;  // no meaningful standard error
    jc[c.name] = e;
  }
  j["fit_quality"] = fit_quality_json(f);
  Json& jt = j["tangent_check"];
  jt = Json::object();
  jt["max_relative_difference_K"] = r.tangent_dK;
  jt["max_relative_difference_G"] = r.tangent_dG;
  j["isotropic_validation"] = validation_json(r.validation);
  return j;
}

// One fit's group of results.h5: its data, constants, the law's curves, the isotropic path.
void write_fit_group(H5Writer& h5, const StudyFit& r) {
  const ModuliData& d = r.data;
  const IsotropicValidation& v = r.validation;
  const std::string g = "/fit/" + r.key;
  // Volume fractions, coordination numbers and fabric traces are pure numbers; moduli and
  // pressures in MPa (K = K* kn_mean / dbar; the preparation's pressure as the study
  // wrote it).
  write_quantity(h5, g + "/data/phi", d.phi, "1");
  write_quantity(h5, g + "/data/z", d.z, "1");
  h5.attribute(g, "data_set", d.name);
  h5.attribute(g, "study", r.set.study);
  write_quantity(h5, g + "/data/fabric", d.fabric, "1");
  write_quantity(h5, g + "/data/K", d.K, "MPa");
  write_quantity(h5, g + "/data/G", d.G, "MPa");
  write_quantity(h5, g + "/data/pressure", d.pressure, "MPa");
  write_quantity(h5, g + "/preparation/phi", d.prep_phi, "1");
  write_quantity(h5, g + "/preparation/pressure", d.prep_pressure, "MPa");
  write_quantity(h5, g + "/preparation/z", d.prep_z, "1");
  write_quantity(h5, g + "/preparation/peak", std::vector<int>{static_cast<int>(d.peak)}, "1");
  std::vector<double> cv;
  for (const FittedConstant& c : r.fit.constants) cv.push_back(c.value);
  h5.write(g + "/constants", cv);
  // The constants differ in unit (nu0, C0, C1, alpha, g3, Fv0, G2 pure numbers; K0, K1,
  // G0, G1 in MPa): no single unit, so each entry's name and unit go beside it.
  std::vector<std::string> cnames, cunits;
  for (const FittedConstant& c : r.fit.constants)
    cnames.push_back(c.name), cunits.push_back(c.unit[0] == '-' ? "1" : c.unit);
  set_unit(h5, g + "/constants", "mixed");
  h5.attribute(g + "/constants", "entry_names", cnames);
  h5.attribute(g + "/constants", "entry_units", cunits);
  write_quantity(h5, g + "/law/nu", r.curves.nu, "1");
  write_quantity(h5, g + "/law/C", r.curves.C, "1");
  write_quantity(h5, g + "/law/Fv", r.curves.Fv, "1");
  write_quantity(h5, g + "/law/K", r.curves.K, "MPa");
  write_quantity(h5, g + "/law/G", r.curves.G, "MPa");
  write_quantity(h5, g + "/isotropic/law_phi", v.law_phi, "1");
  write_quantity(h5, g + "/isotropic/law_p", v.law_p, "MPa");
  write_quantity(h5, g + "/isotropic/loading_phi", v.loading.phi, "1");
  write_quantity(h5, g + "/isotropic/loading_p_dem", v.loading.p_dem, "MPa");
  write_quantity(h5, g + "/isotropic/loading_p_law", v.loading.p_law, "MPa");
  write_quantity(h5, g + "/isotropic/unloading_phi", v.unloading.phi, "1");
  write_quantity(h5, g + "/isotropic/unloading_p_dem", v.unloading.p_dem, "MPa");
  write_quantity(h5, g + "/isotropic/unloading_p_law", v.unloading.p_law, "MPa");
}

// The history in /history and summary.json.
void write_history(H5Writer& h5, Json& summary, const Setup& s, const HistoryRun& h) {
  const PathRecord& r = h.record;
  // The table's time column as given, taken as the engine's time unit (the law is
  // rate-independent: time only places the rows); stresses of the fitted law in MPa.
  write_quantity(h5, "/history/time", h.time, "us");
  write_quantity(h5, "/history/nu", r.nu, "1");
  write_quantity(h5, "/history/pressure", r.pressure, "MPa");
  write_quantity(h5, "/history/deviatoric", r.deviatoric, "MPa");
  write_quantity(h5, "/history/tau", r.tau, "MPa", {r.size(), 9});
  h5.attribute("/history", "fit", h.fit);
  Json& jh = summary["history"];
  jh = Json::object();
  jh["file"] = s.history_file;
  jh["fit"] = h.fit;
  jh["rows"] = static_cast<long>(s.history_table.time.size());
  jh["steps"] = static_cast<long>(r.size() - 1);
  jh["nu_end"] = h.nu_end;
  jh["pressure_end_MPa"] = h.pressure_end;
  jh["von_mises_end_MPa"] = h.von_mises_end;
}

// The shear comparison in /shear and summary.json.
void write_shear(H5Writer& h5, Json& summary, const ShearRun& r) {
  // Axial true strain and coordination numbers are pure numbers; stresses in MPa.
  write_quantity(h5, "/shear/strain", r.strain, "1");
  write_quantity(h5, "/shear/p_dem", r.p_dem, "MPa");
  write_quantity(h5, "/shear/p_law", r.p_law, "MPa");
  write_quantity(h5, "/shear/dev_dem", r.d_dem, "MPa");
  write_quantity(h5, "/shear/dev_law", r.d_law, "MPa");
  write_quantity(h5, "/shear/z_dem", r.dem.z, "1");
  h5.attribute("/shear", "fit", r.fit);
  Json& js = summary["shear_validation"];
  js = Json::object();
  js["fit"] = r.fit;
  js["dem"] =
      "fresh run: frictionless linear preparation to shear.phi (loading branch), "
      "relaxed, then isochoric pure shear (compress x, stretch y) with tangential "
      "springs and friction shear.mu";
  js["phi"] = r.dem.phi;
  js["z_corrected"] = r.dem.z_corrected;
  js["initial_pressure_MPa"] = r.dem.pressure.front();
  js["largest_axial_strain"] = r.strain.back();
  js["mean_stress_rms_error_MPa"] = r.mean_stress_rms;
  js["deviator_rms_error_MPa"] = r.deviator_rms;
  js["deviator_max_abs_error_MPa"] = r.deviator_max;
  js["deviator_dem_end_MPa"] = r.d_dem.back();
  js["deviator_law_end_MPa"] = r.d_law.back();
  js["deviator_initial_slope_dem_over_law"] = (r.d_dem[1] - r.d_dem[0]) / (r.d_law[1] - r.d_law[0]);
  js["strain_where_deviator_error_exceeds_10_percent"] =
      std::isnan(r.fail_strain) ? Json("never") : Json(r.fail_strain);
}

// results.h5 and summary.json (constants.txt is written before: write_constants).
void write_results(SceneOutput& output, const Setup& s, const ContinuumResults& r,
                   std::chrono::steady_clock::time_point t0) {
  H5Writer& h5 = output.h5();
  Json& summary = output.summary();
  summary["volume_fraction_update"] = to_string(s.update);
  write_example(h5, summary, r.example);
  Json& jf = summary["fits"];
  jf = Json::array();
  for (const StudyFit& f : r.fits) {
    jf.push(fit_entry(f));
    write_fit_group(h5, f);
  }
  if (r.history) write_history(h5, summary, s, *r.history);
  if (r.shear) write_shear(h5, summary, *r.shear);
  summary["wall_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

void check_continuum_fit(const SceneFile& scene) { read_setup(scene); }

void run_continuum_fit(const SceneFile& scene, const RunOptions& opts) {
  const Setup s = read_setup(scene);
  const auto t0 = std::chrono::steady_clock::now();
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "continuum_fit");
  output.h5();  // the partial results.h5 made now: an unwritable folder fails before the run
  ContinuumResults r;
  r.example = spec_example(s);
  r.fits = fit_studies(scene, s);
  write_constants(output, scene, s, r.fits);
  if (!s.history_file.empty()) r.history = drive_history(scene, s, r.fits);
  if (s.shear) r.shear = validate_shear(scene, s, r.fits);
  write_results(output, s, r, t0);
  output.finish();
}

}  // namespace granular
