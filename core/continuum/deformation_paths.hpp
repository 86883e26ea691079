// Prescribed deformation paths for a material point: per-step increments of isotropic
// compression/decompression, pure shear, uniaxial strain and rigid rotation, deformation
// gradient histories read from a table, and the record of a driven path.
#pragma once
#include <string>
#include <vector>

#include "core/continuum/material_point.hpp"

namespace granular {

enum class PathKind { isotropic, pure_shear, uniaxial, rotation };
PathKind path_kind_from(const std::string& name);  // throws InputError naming the kinds

// Relative deformation gradient of one step. `d` is the stretch increment: isotropic
// f = (1 + d) 1 (d < 0 compresses); pure shear f = diag(1 + d, 1/(1 + d), 1), isochoric;
// uniaxial f = diag(1 + d, 1, 1); rotation: by the angle d about the z axis.
Mat3 step_increment(PathKind kind, double d);

// Stress and state after every step of a path (entry 0: the start).
struct PathRecord {
  std::vector<double> nu, J, pressure, deviatoric, K, G;
  std::vector<double> tau;  // Kirchhoff stress, 9 per entry, row-major
  void add(const MaterialPoint& p);
  size_t size() const { return nu.size(); }
};

// Applies f for `steps` steps.
PathRecord drive(MaterialPoint& p, const Mat3& f, long steps);
// Applies f until nu crosses nu_target (at most max_steps; InputError when it does not
// move towards the target).
PathRecord drive_to_volume_fraction(MaterialPoint& p, const Mat3& f, double nu_target,
                                    long max_steps = 100000000);

// Tangent moduli of the update by central differences of the Cauchy stress over +-eta of
// true strain from a stress-free point at nu (isotropic for K, isochoric pure shear for G,
// uniaxial for M): what an FE code sees from one step, to compare with K(nu), G(nu).
struct TangentModuli {
  double K = 0, G = 0, M = 0;
};
TangentModuli numerical_tangent(const ContinuumConstants& law, double nu, VolumeFractionUpdate u,
                                double eta = 1e-5);

// A deformation-gradient history: rows of time and F (row-major F11 F12 F13 F21 ... F33).
struct DeformationTable {
  std::vector<double> time;
  std::vector<Mat3> F;
};
// Text table, one row per line, values separated by commas and/or white space; blank lines
// and lines starting with '#' are skipped, and so is a first line that is not numeric (a
// header). Wrong column counts, non-numbers and decreasing times are errors naming the file
// and line.
DeformationTable read_deformation_table(const std::string& path);
DeformationTable parse_deformation_table(const std::string& text, const std::string& source);
// Drives the point through the table's rows, `substeps` steps per interval with F linear in
// time between rows. The first row must be the point's current F.
PathRecord drive_table(MaterialPoint& p, const DeformationTable& table, int substeps = 1);

}  // namespace granular
