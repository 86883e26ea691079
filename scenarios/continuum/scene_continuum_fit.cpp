// Scene `continuum_fit`: the continuum law of docs/model_continuum.md fitted to the engine's own
// elastic-moduli studies and checked against DEM paths, in one run:
//   parse -> spec example (regression of the source's isotropic path) -> fit each study and
//   preparation friction -> isotropic validation on the preparation path -> DEM pure shear
//   against the law -> write (results.h5, summary.json, constants.txt, charts).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <map>
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
    DemShearSpec& d = s.dem;
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
    scene.require(d.phi > d.gas.phi && d.phi < 0.9, "shear.phi",
                  "must lie in (shear.phi_gas, 0.9)");
    scene.require(d.strain > 0 && d.strain < 0.2, "shear.strain", "must lie in (0, 0.2)");
    scene.require(d.strain_rate > 0, "shear.strain_rate", "must be positive");
    scene.require(d.volumetric_strain_rate > 0, "shear.volumetric_strain_rate", "must be positive");
    scene.require(d.samples >= 2, "shear.samples", "must be at least 2");
    scene.require(d.mu >= 0, "shear.mu", "must not be negative");
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

// 1. The source's example: isotropic compression from nu0 to nu_end, both nu updates.
void write_spec_example(const Setup& s, H5Writer& h5, Json& summary) {
  Json& ex = summary["spec_example"];
  ex = Json::object();
  const ContinuumConstants c = ContinuumConstants::spec_example();
  ex["constants_units"] = c.units;
  double p_end[2];
  int k = 0;
  for (VolumeFractionUpdate u :
       {VolumeFractionUpdate::mass_conservation, VolumeFractionUpdate::exponential}) {
    MaterialPoint p(c, c.nu0, u);
    const PathRecord r = drive_to_volume_fraction(
        p, step_increment(PathKind::isotropic, s.example_step), s.example_nu_end);
    const std::string g = std::string("/example/") + to_string(u);
    // The source prints K0, K1, G0, G1 without a unit (docs/model_continuum.md §6): the
    // example's pressure and K are numbers in that unprinted stress unit, labelled "1".
    write_quantity(h5, g + "/nu", r.nu, "1");
    write_quantity(h5, g + "/pressure", r.pressure, "1");
    write_quantity(h5, g + "/K", r.K, "1");
    Json& e = ex[to_string(u)];
    e = Json::object();
    e["steps"] = static_cast<long>(r.size() - 1);
    e["nu_end"] = p.nu();
    e["J_end"] = p.J();
    e["cauchy_pressure_end"] = p.pressure();
    e["kirchhoff_pressure_end"] = p.pressure() * p.J();
    p_end[k++] = p.pressure();
  }
  ex["exponential_over_mass_conservation_pressure"] = p_end[1] / p_end[0];
}

// One fit's entry of summary.json (its constants also as lines of constants.txt).
Json fit_entry(const DataSet& set, const ModuliData& d, const std::string& key,
               const ContinuumFit& f, const IsotropicValidation& v, const Setup& s,
               std::ostringstream& constants_txt) {
  Json j = Json::object();
  j["key"] = key;
  j["data_set"] = d.name;
  j["study"] = set.study;
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
  constants_txt << "\n[" << d.name << "]  # study " << set.study << "\n";
  for (const FittedConstant& c : f.constants) {
    Json e = Json::object();
    e["value"] = c.value;
    e["std_error"] = c.std_error;
    e["unit"] = c.unit;
    if (c.at_bound) e["at_bound"] = true;  // no meaningful standard error
    jc[c.name] = e;
    char line[160];
    std::snprintf(line, sizeof line, "%-6s = %-14.8g # +- %.3g %s%s\n", c.name, c.value,
                  c.std_error, c.unit, c.at_bound ? " (at a bound of the fit)" : "");
    constants_txt << line;
  }
  Json& jr = j["fit_quality"];
  jr = Json::object();
  jr["coordination"] = fit_json(f.coordination, "C*(nu) against Z* of the unloading series");
  jr["coordination"]["note"] =
      "points are consecutive samples of one preparation, correlated in time: the standard "
      "errors assume independent residuals and are therefore lower bounds";
  jr["fabric"] = fit_json(f.fabric, "F_v = g3 C* nu against the table's fabric trace");
  jr["bulk"] = fit_json(f.bulk, "K = K0 + K1 (F_v - F_v0), MPa");
  jr["shear"] = fit_json(f.shear, "G = G0 + G1 (F_v - F_v0)^G2, MPa");
  // The update's own tangent at the data's volume fractions against K(nu), G(nu): what an
  // FE code integrating this law sees in one step.
  double dK = 0, dG = 0;
  for (double phi : d.phi) {
    const ContinuumModuli m = continuum_moduli(f.law, phi);
    const TangentModuli t = numerical_tangent(f.law, phi, s.update);
    if (m.K > 0) dK = std::max(dK, std::abs(t.K - m.K) / m.K);
    if (m.G > 0) dG = std::max(dG, std::abs(t.G - m.G) / m.G);
  }
  Json& jt = j["tangent_check"];
  jt = Json::object();
  jt["max_relative_difference_K"] = dK;
  jt["max_relative_difference_G"] = dG;
  Json& jv = j["isotropic_validation"];
  jv = Json::object();
  jv["path"] =
      "law compressed from nu0 (stress-free) to the series' largest phi, then decompressed; "
      "DEM: /preparation pressure of this friction (loading at the preparation rate, then "
      "unloading), and the relaxed configurations of /table";
  jv["loading"] = branch_json(v.loading);
  jv["unloading"] = branch_json(v.unloading);
  jv["configurations"] = branch_json(v.configurations);
  jv["configurations"]["per_configuration"] = per_point_relative(v.configurations);
  return j;
}

// One fit's group of results.h5: its data, constants, the law's curves, the isotropic path.
void write_fit_group(H5Writer& h5, const DataSet& set, const ModuliData& d, const std::string& key,
                     const ContinuumFit& f, const IsotropicValidation& v) {
  const std::string g = "/fit/" + key;
  // Volume fractions, coordination numbers and fabric traces are pure numbers; moduli and
  // pressures in MPa (K = K* kn_mean / dbar; the preparation's pressure as the study
  // wrote it).
  write_quantity(h5, g + "/data/phi", d.phi, "1");
  write_quantity(h5, g + "/data/z", d.z, "1");
  h5.attribute(g, "data_set", d.name);
  h5.attribute(g, "study", set.study);
  write_quantity(h5, g + "/data/fabric", d.fabric, "1");
  write_quantity(h5, g + "/data/K", d.K, "MPa");
  write_quantity(h5, g + "/data/G", d.G, "MPa");
  write_quantity(h5, g + "/data/pressure", d.pressure, "MPa");
  write_quantity(h5, g + "/preparation/phi", d.prep_phi, "1");
  write_quantity(h5, g + "/preparation/pressure", d.prep_pressure, "MPa");
  write_quantity(h5, g + "/preparation/z", d.prep_z, "1");
  write_quantity(h5, g + "/preparation/peak", std::vector<int>{static_cast<int>(d.peak)}, "1");
  std::vector<double> cv;
  for (const FittedConstant& c : f.constants) cv.push_back(c.value);
  h5.write(g + "/constants", cv);
  // The constants differ in unit (nu0, C0, C1, alpha, g3, Fv0, G2 pure numbers; K0, K1,
  // G0, G1 in MPa): no single unit, so each entry's name and unit go beside it.
  std::vector<std::string> cnames, cunits;
  for (const FittedConstant& c : f.constants)
    cnames.push_back(c.name), cunits.push_back(c.unit[0] == '-' ? "1" : c.unit);
  set_unit(h5, g + "/constants", "mixed");
  h5.attribute(g + "/constants", "entry_names", cnames);
  h5.attribute(g + "/constants", "entry_units", cunits);
  // The law's curves over the data's range, for the charts.
  std::vector<double> nu, C, Fv, K, G;
  for (int i = 0; i <= 400; ++i) {
    const double x = f.law.nu0 + (d.prep_phi[d.peak] - f.law.nu0) * i / 400.0;
    const ContinuumModuli m = continuum_moduli(f.law, x);
    nu.push_back(x), C.push_back(m.C), Fv.push_back(m.Fv), K.push_back(m.K), G.push_back(m.G);
  }
  write_quantity(h5, g + "/law/nu", nu, "1");
  write_quantity(h5, g + "/law/C", C, "1");
  write_quantity(h5, g + "/law/Fv", Fv, "1");
  write_quantity(h5, g + "/law/K", K, "MPa");
  write_quantity(h5, g + "/law/G", G, "MPa");
  write_quantity(h5, g + "/isotropic/law_phi", v.law_phi, "1");
  write_quantity(h5, g + "/isotropic/law_p", v.law_p, "MPa");
  write_quantity(h5, g + "/isotropic/loading_phi", v.loading.phi, "1");
  write_quantity(h5, g + "/isotropic/loading_p_dem", v.loading.p_dem, "MPa");
  write_quantity(h5, g + "/isotropic/loading_p_law", v.loading.p_law, "MPa");
  write_quantity(h5, g + "/isotropic/unloading_phi", v.unloading.phi, "1");
  write_quantity(h5, g + "/isotropic/unloading_p_dem", v.unloading.p_dem, "MPa");
  write_quantity(h5, g + "/isotropic/unloading_p_law", v.unloading.p_law, "MPa");
}

// 2. Fits and the isotropic validation, per study and preparation friction; writes
// constants.txt. Returns the fitted laws by key (data set and preparation friction).
std::map<std::string, ContinuumFit> fit_studies(const SceneFile& scene, const Setup& s,
                                                SceneOutput& output) {
  std::map<std::string, ContinuumFit> fits;
  Json& jf = output.summary()["fits"];
  jf = Json::array();
  std::ostringstream constants_txt;
  constants_txt << "# Continuum-law constants (continuum.md) fitted by the continuum_fit scene ("
                << scene.path() << ").\n"
                << "# K = K0 + K1 (F_v - F_v0), G = G0 + G1 (F_v - F_v0)^G2 in MPa (N/mm^2);\n"
                << "# C* = C0 + C1 (nu/nu0 - 1)^alpha (0 below nu0), F_v = C* g3 nu.\n"
                << "# Volume fraction update used in the validation: " << to_string(s.update)
                << ". Below nu0: K = G = 0 and no stress; for F_v < F_v0: G = G0.\n";
  for (const DataSet& set : s.data) {
    for (const ModuliData& d : read_moduli_study(set.study, set.name)) {
      const std::string key = key_of(d, set.name);
      std::cerr << "fitting " << d.name << " (" << set.study << ")\n";
      const ContinuumFit f = fit_continuum_law(d, s.z_min);
      // The validation path keeps 15 doubles per law step (twice that while growing):
      // refused naming the key rather than allocating gigabytes for a tiny step.
      if (!d.prep_phi.empty() && f.law.nu0 > 0) {
        const double lo = *std::min_element(d.prep_phi.begin(), d.prep_phi.end()),
                     hi = *std::max_element(d.prep_phi.begin(), d.prep_phi.end());
        const double span = std::abs(std::log(hi / f.law.nu0)) + std::abs(std::log(hi / lo));
        scene.require_memory("law.step", (span / (3 * s.step) + 2) * 15 * 8 * 2);
      }
      const IsotropicValidation v = validate_isotropic(d, f.law, s.update, s.step);
      fits[key] = f;
      jf.push(fit_entry(set, d, key, f, v, s, constants_txt));
      write_fit_group(output.h5(), set, d, key, f, v);
    }
  }
  write_text_file(output.path("constants.txt"), constants_txt.str());
  return fits;
}

using Fits = std::map<std::string, ContinuumFit>;

// The fit of data set `data` at preparation friction `mu`, as the table [table] names it
// (keys <table>.data and <table>.fit_mu); an input error when no such fit was made.
Fits::const_iterator fit_named(const SceneFile& scene, const Fits& fits, const std::string& table,
                               const std::string& data, double mu) {
  std::ostringstream k;
  k << data << "_mu" << mu;
  const auto it = fits.find(k.str());
  if (it == fits.end())
    throw InputError(scene.path() + ": " + table + ".data / " + table +
                     ".fit_mu name no fitted data set (" + k.str() + ")");
  return it;
}

// 3. A tabulated deformation history through one fitted law.
void drive_history(const SceneFile& scene, const Setup& s,
                   const std::map<std::string, ContinuumFit>& fits, H5Writer& h5, Json& summary) {
  const auto it = fit_named(scene, fits, "history", s.history_data, s.history_fit_mu);
  const DeformationTable& table = s.history_table;
  MaterialPoint p(it->second.law, s.history_nu_start, s.update);
  const PathRecord r = drive_table(p, table, s.history_substeps);
  std::vector<double> time = {table.time.front()};
  for (size_t row = 1; row < table.time.size(); ++row)
    for (int q = 1; q <= s.history_substeps; ++q)
      time.push_back(table.time[row - 1] +
                     (table.time[row] - table.time[row - 1]) * q / s.history_substeps);
  // The table's time column as given, taken as the engine's time unit (the law is
  // rate-independent: time only places the rows); stresses of the fitted law in MPa.
  write_quantity(h5, "/history/time", time, "us");
  write_quantity(h5, "/history/nu", r.nu, "1");
  write_quantity(h5, "/history/pressure", r.pressure, "MPa");
  write_quantity(h5, "/history/deviatoric", r.deviatoric, "MPa");
  write_quantity(h5, "/history/tau", r.tau, "MPa", {r.size(), 9});
  h5.attribute("/history", "fit", it->first);
  Json& jh = summary["history"];
  jh = Json::object();
  jh["file"] = s.history_file;
  jh["fit"] = it->first;
  jh["rows"] = static_cast<long>(table.time.size());
  jh["steps"] = static_cast<long>(r.size() - 1);
  jh["nu_end"] = p.nu();
  jh["pressure_end_MPa"] = p.pressure();
  jh["von_mises_end_MPa"] = p.deviatoric();
}

// 4. DEM pure shear against the law fitted to the matching preparation.
void validate_shear(const SceneFile& scene, const Setup& s,
                    const std::map<std::string, ContinuumFit>& fits, H5Writer& h5, Json& summary) {
  const auto it = fit_named(scene, fits, "shear", s.shear_data, s.shear_fit_mu);
  const ContinuumConstants& law = it->second.law;
  std::cerr << "DEM pure shear (" << s.dem.gas.count << " particles, phi " << s.dem.phi << ")\n";
  const DemShearPath dem = run_dem_pure_shear(s.dem);
  // The law starts from the DEM's own stress and volume fraction and follows the box's F
  // (10 sub-steps per sample); stresses compared as mean stress and the xx - yy deviator.
  Mat3 tau0 = Mat3::Zero();
  tau0(0, 0) = -dem.sxx[0], tau0(1, 1) = -dem.syy[0], tau0(2, 2) = -dem.szz[0];
  tau0(0, 1) = tau0(1, 0) = -dem.sxy[0], tau0(0, 2) = tau0(2, 0) = -dem.sxz[0];
  tau0(1, 2) = tau0(2, 1) = -dem.syz[0];
  MaterialPoint p(law, dem.phi, s.update, tau0);
  std::vector<double> strain, p_dem, p_law, d_dem, d_law, err_p, err_d;
  const int sub = 10;
  double rms_p = 0, rms_d = 0, max_d = 0;
  double fail_strain = NAN;
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
    strain.push_back(-std::log(dem.stretch_x[i]));
    p_dem.push_back(dem.pressure[i]), p_law.push_back(sig.trace() / 3);
    d_dem.push_back(dem.sxx[i] - dem.syy[i]), d_law.push_back(sig(0, 0) - sig(1, 1));
    err_p.push_back(p_law.back() - p_dem.back()), err_d.push_back(d_law.back() - d_dem.back());
    rms_p += err_p.back() * err_p.back(), rms_d += err_d.back() * err_d.back();
    max_d = std::max(max_d, std::abs(err_d.back()));
    // First strain where the deviator misses the DEM's by more than 10 % of the DEM's.
    const double growth = d_dem.back() - d_dem.front();
    if (std::isnan(fail_strain) && i > 0 &&
        std::abs(err_d.back() - err_d.front()) > 0.1 * std::abs(growth))
      fail_strain = strain.back();
  }
  const double n = static_cast<double>(strain.size());
  // Axial true strain and coordination numbers are pure numbers; stresses in MPa.
  write_quantity(h5, "/shear/strain", strain, "1");
  write_quantity(h5, "/shear/p_dem", p_dem, "MPa");
  write_quantity(h5, "/shear/p_law", p_law, "MPa");
  write_quantity(h5, "/shear/dev_dem", d_dem, "MPa");
  write_quantity(h5, "/shear/dev_law", d_law, "MPa");
  write_quantity(h5, "/shear/z_dem", dem.z, "1");
  h5.attribute("/shear", "fit", it->first);
  Json& js = summary["shear_validation"];
  js = Json::object();
  js["fit"] = it->first;
  js["dem"] =
      "fresh run: frictionless linear preparation to shear.phi (loading branch), "
      "relaxed, then isochoric pure shear (compress x, stretch y) with tangential "
      "springs and friction shear.mu";
  js["phi"] = dem.phi;
  js["z_corrected"] = dem.z_corrected;
  js["initial_pressure_MPa"] = dem.pressure.front();
  js["largest_axial_strain"] = strain.back();
  js["mean_stress_rms_error_MPa"] = std::sqrt(rms_p / n);
  js["deviator_rms_error_MPa"] = std::sqrt(rms_d / n);
  js["deviator_max_abs_error_MPa"] = max_d;
  js["deviator_dem_end_MPa"] = d_dem.back();
  js["deviator_law_end_MPa"] = d_law.back();
  js["deviator_initial_slope_dem_over_law"] = (d_dem[1] - d_dem[0]) / (d_law[1] - d_law[0]);
  js["strain_where_deviator_error_exceeds_10_percent"] =
      std::isnan(fail_strain) ? Json("never") : Json(fail_strain);
}
}  // namespace

void check_continuum_fit(const SceneFile& scene) { read_setup(scene); }

void run_continuum_fit(const SceneFile& scene, const RunOptions& opts) {
  const Setup s = read_setup(scene);
  const auto t0 = std::chrono::steady_clock::now();
  if (!begin_outputs(opts)) return;
  SceneOutput output(scene, opts, "continuum_fit");
  output.summary()["volume_fraction_update"] = to_string(s.update);
  write_spec_example(s, output.h5(), output.summary());
  const std::map<std::string, ContinuumFit> fits = fit_studies(scene, s, output);
  if (!s.history_file.empty()) drive_history(scene, s, fits, output.h5(), output.summary());
  if (s.shear) validate_shear(scene, s, fits, output.h5(), output.summary());
  output.summary()["wall_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  output.finish();
}

}  // namespace granular
