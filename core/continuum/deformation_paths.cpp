// Deformation paths and the deformation-gradient table reader.
#include "core/continuum/deformation_paths.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/run/error.hpp"

namespace granular {

PathKind path_kind_from(const std::string& name) {
  if (name == "isotropic") return PathKind::isotropic;
  if (name == "pure_shear") return PathKind::pure_shear;
  if (name == "uniaxial") return PathKind::uniaxial;
  if (name == "rotation") return PathKind::rotation;
  throw InputError("path '" + name +
                   "' is unknown: use isotropic, pure_shear, uniaxial or rotation");
}

Mat3 step_increment(PathKind kind, double d) {
  Mat3 f = Mat3::Identity();
  switch (kind) {
    case PathKind::isotropic:
      f *= 1.0 + d;
      break;
    case PathKind::pure_shear:
      f(0, 0) = 1.0 + d, f(1, 1) = 1.0 / (1.0 + d);
      break;
    case PathKind::uniaxial:
      f(0, 0) = 1.0 + d;
      break;
    case PathKind::rotation:
      f(0, 0) = f(1, 1) = std::cos(d);
      f(0, 1) = -std::sin(d), f(1, 0) = std::sin(d);
      break;
  }
  return f;
}

void PathRecord::add(const MaterialPoint& p) {
  nu.push_back(p.nu());
  J.push_back(p.J());
  pressure.push_back(p.pressure());
  deviatoric.push_back(p.deviatoric());
  K.push_back(p.last_moduli().K);
  G.push_back(p.last_moduli().G);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) tau.push_back(p.kirchhoff()(i, j));
}

PathRecord drive(MaterialPoint& p, const Mat3& f, long steps) {
  PathRecord r;
  r.add(p);
  for (long s = 0; s < steps; ++s) {
    p.step_by(f);
    r.add(p);
  }
  return r;
}

PathRecord drive_to_volume_fraction(MaterialPoint& p, const Mat3& f, double nu_target,
                                    long max_steps) {
  const bool up = nu_target > p.nu();
  if (up != (f.determinant() < 1.0))
    throw InputError("material point: the step moves the volume fraction away from its target");
  PathRecord r;
  r.add(p);
  for (long s = 0; s < max_steps && (up ? p.nu() < nu_target : p.nu() > nu_target); ++s) {
    p.step_by(f);
    r.add(p);
  }
  return r;
}

TangentModuli numerical_tangent(const ContinuumConstants& law, double nu, VolumeFractionUpdate u,
                                double eta) {
  auto sigma = [&](double a, double b, double c) {
    MaterialPoint p(law, nu, u);
    p.step_to(Eigen::Vector3d(std::exp(a), std::exp(b), std::exp(c)).asDiagonal());
    return p.cauchy();
  };
  TangentModuli t;
  t.K = (sigma(eta, eta, eta).trace() - sigma(-eta, -eta, -eta).trace()) / 3 / (6 * eta);
  const Mat3 up = sigma(eta, -eta, 0), down = sigma(-eta, eta, 0);
  t.G = ((up(0, 0) - up(1, 1)) - (down(0, 0) - down(1, 1))) / (8 * eta);
  t.M = (sigma(eta, 0, 0)(0, 0) - sigma(-eta, 0, 0)(0, 0)) / (2 * eta);
  return t;
}

DeformationTable parse_deformation_table(const std::string& text, const std::string& source) {
  DeformationTable t;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  bool first_data_line = true;
  while (std::getline(in, line)) {
    ++line_no;
    for (char& ch : line)
      if (ch == ',' || ch == ';' || ch == '\t' || ch == '\r') ch = ' ';
    const size_t start = line.find_first_not_of(' ');
    if (start == std::string::npos || line[start] == '#') continue;
    std::istringstream row(line);
    std::vector<double> v;
    std::string cell;
    bool numeric = true;
    while (row >> cell) {
      char* end = nullptr;
      const double x = std::strtod(cell.c_str(), &end);
      if (end == cell.c_str() || *end != '\0') numeric = false;
      v.push_back(x);
    }
    auto fail = [&](const std::string& what) {
      throw InputError(source + " line " + std::to_string(line_no) + ": " + what);
    };
    if (!numeric) {
      if (first_data_line) {  // a header row naming the columns
        first_data_line = false;
        continue;
      }
      fail("not a number");
    }
    first_data_line = false;
    if (v.size() != 10)
      fail("expected 10 values (time and 9 components of F), got " + std::to_string(v.size()));
    for (double x : v)
      if (!std::isfinite(x)) fail("not a finite number (nan, inf or beyond the doubles)");
    if (!t.time.empty() && !(v[0] > t.time.back())) fail("time must increase");
    Mat3 F;
    for (int k = 0; k < 9; ++k) F(k / 3, k % 3) = v[1 + k];
    if (!(F.determinant() > 0) || !std::isfinite(F.determinant()))
      fail("det F must be positive and finite");
    t.time.push_back(v[0]);
    t.F.push_back(F);
  }
  if (t.time.size() < 2) throw InputError(source + ": a deformation table needs at least 2 rows");
  return t;
}

DeformationTable read_deformation_table(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot read deformation table " + path);
  std::stringstream buf;
  buf << in.rdbuf();
  return parse_deformation_table(buf.str(), path);
}

PathRecord drive_table(MaterialPoint& p, const DeformationTable& table, int substeps) {
  if (substeps < 1) throw InputError("deformation table: substeps must be at least 1");
  if (!(table.F.front() - p.F()).isZero(1e-12))
    throw InputError("deformation table: the first row must be the point's current F");
  PathRecord r;
  r.add(p);
  for (size_t row = 1; row < table.F.size(); ++row)
    for (int s = 1; s <= substeps; ++s) {
      const double w = static_cast<double>(s) / substeps;
      p.step_to((1.0 - w) * table.F[row - 1] + w * table.F[row]);
      r.add(p);
    }
  return r;
}

}  // namespace granular
