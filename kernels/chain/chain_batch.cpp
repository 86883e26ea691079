// Disorder draws and option parsing for batched chains.
#include "kernels/chain/chain_batch.hpp"

namespace granular {

namespace {
[[noreturn]] void bad_option(const std::string& what, const std::string& value,
                             const std::string& allowed) {
  throw InputError("unknown chain " + what + " '" + value + "' (use " + allowed + ")");
}
}  // namespace

ChainBoundary parse_chain_boundary(const std::string& s) {
  if (s == "fixed") return ChainBoundary::Fixed;
  if (s == "periodic") return ChainBoundary::Periodic;
  bad_option("boundary", s, "fixed or periodic");
}

ChainForce parse_chain_force(const std::string& s) {
  if (s == "hertz") return ChainForce::Hertz;
  if (s == "linear") return ChainForce::Linear;
  bad_option("force law", s, "hertz or linear");
}

StiffnessRule parse_stiffness_rule(const std::string& s) {
  if (s == "radius") return StiffnessRule::Radius;
  if (s == "mass") return StiffnessRule::Mass;
  bad_option("stiffness rule", s, "radius or mass");
}

DisorderTarget parse_disorder_target(const std::string& s) {
  if (s == "mass_and_stiffness") return DisorderTarget::MassAndStiffness;
  if (s == "mass_only") return DisorderTarget::MassOnly;
  bad_option("disorder target", s, "mass_and_stiffness or mass_only");
}

ChainKernel parse_chain_kernel(const std::string& s) {
  if (s == "auto") return ChainKernel::Auto;
  if (s == "global") return ChainKernel::Global;
  if (s == "on_chip") return ChainKernel::OnChip;
  bad_option("kernel", s, "auto, global or on_chip");
}

std::vector<double> chain_masses(const ChainSpec& spec, std::uint64_t realization) {
  if (spec.xi < 0) throw InputError("disorder xi must not be negative");
  if (spec.min_mass < 0 || spec.min_mass >= 1)
    throw InputError("minimum mass must be in [0, 1) (the mean mass is 1)");
  std::vector<double> m(spec.beads, 1.0);
  if (spec.xi == 0.0) return m;  // ordered chain: exactly 1, no rescaling round-off
  Stream rng(spec.seed, realization);
  double sum = 0.0;
  for (double& x : m) {
    do {
      x = 1.0 + spec.xi * rng.normal();
    } while (x <= spec.min_mass);
    sum += x;
  }
  const double scale = spec.beads / sum;
  for (double& x : m) x *= scale;
  return m;
}

double chain_pair_kappa(StiffnessRule rule, double bi, double bj) {
  const double sum = rule == StiffnessRule::Radius ? std::cbrt(bi) + std::cbrt(bj) : bi + bj;
  return std::sqrt(2.0 / sum) * std::pow(bi * bj, 1.0 / 6.0);
}

}  // namespace granular
