// LAMMPS granular pair styles (see lammps_pair_styles.hpp).
#include "core/lammps/lammps_pair_styles.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/run/error.hpp"

namespace granular {

namespace {

std::vector<std::string> words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> w;
  for (std::string t; in >> t;) w.push_back(t);
  return w;
}

double number(const std::string& where, const std::string& w) {
  try {
    size_t used = 0;
    const double x = std::stod(w, &used);
    if (used == w.size() && std::isfinite(x)) return x;
  } catch (const std::exception&) {
  }
  throw InputError(where + ": '" + w + "' is not a number");
}

// LAMMPS' type ranges: "*", "n", "n*", "*n", "m*n".
void bounds(const std::string& where, const std::string& w, int ntypes, int& lo, int& hi) {
  auto one = [&](const std::string& t, int def) {
    if (t.empty()) return def;
    const double x = number(where, t);
    if (x != std::floor(x)) throw InputError(where + ": type '" + t + "' is not an integer");
    return static_cast<int>(x);
  };
  const auto star = w.find('*');
  if (star == std::string::npos)
    lo = hi = one(w, 0);
  else
    lo = one(w.substr(0, star), 1), hi = one(w.substr(star + 1), ntypes);
  if (lo < 1 || hi > ntypes || lo > hi)
    throw InputError(where + ": type range '" + w + "' outside 1.." + std::to_string(ntypes));
}

// 1/E* of two Hertzian bodies, and the Mindlin counterpart 1/G*, as `granular` mixes them.
double mix_e(double Ei, double Ej, double ni, double nj) {
  return 1 / ((1 - ni * ni) / Ei + (1 - nj * nj) / Ej);
}
double mix_g(double Ei, double Ej, double ni, double nj) {
  return 1 / ((2 * (2 - ni) * (1 + ni) / Ei) + (2 * (2 - nj) * (1 + nj) / Ej));
}

// Tsuji's damping coefficient from the restitution coefficient (LAMMPS' polynomial fit).
double tsuji_damping(double e) {
  return 1.2728 - 4.2783 * e + 11.087 * e * e - 22.348 * e * e * e + 27.467 * std::pow(e, 4) -
         18.022 * std::pow(e, 5) + 4.8218 * std::pow(e, 6);
}

void parse_classic(LammpsPairModel& m, const std::vector<std::string>& a, const LammpsUnits& u,
                   const std::string& where) {
  if (a.size() != 7 && a.size() != 8)
    throw InputError(where + ": " + a[0] +
                     " needs: kn kt|NULL gamma_n gamma_t|NULL xmu dampflag [limit_damping]");
  m.kn = number(where, a[1]);
  m.kt = a[2] == "NULL" ? m.kn * 2.0 / 7.0 : number(where, a[2]);
  m.gamman = number(where, a[3]);
  m.gammat = a[4] == "NULL" ? 0.5 * m.gamman : number(where, a[4]);
  m.xmu = number(where, a[5]);
  const double df = number(where, a[6]);
  if (df != 0 && df != 1) throw InputError(where + ": dampflag must be 0 or 1");
  m.dampflag = static_cast<int>(df);
  if (m.dampflag == 0) m.gammat = 0;
  if (a.size() == 8) {
    if (a[7] != "limit_damping")
      throw InputError(where + ": the optional last argument is 'limit_damping', not '" + a[7] +
                       "'");
    m.limit_damping = true;
  }
  if (m.kn < 0 || m.kt < 0 || m.gamman < 0 || m.gammat < 0 || m.xmu < 0 || m.xmu > 10000)
    throw InputError(where + ": stiffnesses and dampings must not be negative, 0 <= xmu <= 10000");
  // gran/hertz/history takes its stiffnesses in pressure units.
  if (m.style == LammpsStyle::GranHertzHistory) m.kn /= u.nktv2p, m.kt /= u.nktv2p;
}

// `damping <model>` at a[k]; returns the index after it.
size_t parse_granular_damping(const std::vector<std::string>& a, size_t k, const std::string& where,
                              GranularPair& p) {
  const std::string& d = a[k + 1];
  if (d == "velocity")
    p.damping = GranularPair::Velocity;
  else if (d == "mass_velocity")
    p.damping = GranularPair::MassVelocity;
  else if (d == "viscoelastic")
    p.damping = GranularPair::Viscoelastic;
  else if (d == "tsuji")
    p.damping = GranularPair::Tsuji;
  else
    throw InputError(where + ": damping model '" + d +
                     "' is not one of velocity, "
                     "mass_velocity, viscoelastic, tsuji");
  return k + 2;
}

// `tangential <model> <coefficients>` at a[k]; returns the index after it. `kt_null` says
// whether mindlin's stiffness was given as NULL (derived from E and nu once all is read).
size_t parse_granular_tangential(const std::vector<std::string>& a, size_t k,
                                 const std::string& where, GranularPair& p, bool& kt_null) {
  auto need = [&](size_t n, const std::string& what) {
    if (k + n >= a.size()) throw InputError(where + ": '" + a[k] + "' needs " + what);
  };
  const std::string& t = a[k + 1];
  if (t == "linear_nohistory") {
    need(3, "x_gammat and mu");
    p.tangential = GranularPair::LinearNoHistory;
    p.kt = 0, p.xgt = number(where, a[k + 2]), p.mu = number(where, a[k + 3]);
    return k + 4;
  }
  if (t == "linear_history" || t == "mindlin") {
    need(4, "kt (mindlin: or NULL), x_gammat and mu");
    p.tangential = t == "mindlin" ? GranularPair::Mindlin : GranularPair::LinearHistory;
    kt_null = t == "mindlin" && a[k + 2] == "NULL";
    p.kt = kt_null ? 0 : number(where, a[k + 2]);
    p.xgt = number(where, a[k + 3]), p.mu = number(where, a[k + 4]);
    return k + 5;
  }
  throw InputError(where + ": tangential model '" + t +
                   "' is not supported (supported: "
                   "linear_nohistory, linear_history, mindlin)");
}

GranularPair parse_granular_coeff(const std::vector<std::string>& a, size_t k,
                                  const std::string& where) {
  GranularPair p;
  bool normal = false, tangential = false, kt_null = false;
  double E = 0, nu = 0;
  auto need = [&](size_t n, const std::string& what) {
    if (k + n >= a.size()) throw InputError(where + ": '" + a[k] + "' needs " + what);
  };
  while (k < a.size()) {
    const std::string& w = a[k];
    if (w == "hooke" || w == "hertz") {
      need(2, "a stiffness and a damping coefficient");
      p.normal = w == "hooke" ? GranularPair::Hooke : GranularPair::Hertz;
      p.kn = number(where, a[k + 1]), p.damp = number(where, a[k + 2]);
      normal = true, k += 3;
    } else if (w == "hertz/material") {
      need(3, "E, a damping coefficient and Poisson's ratio");
      p.normal = GranularPair::HertzMaterial;
      E = number(where, a[k + 1]), p.damp = number(where, a[k + 2]), nu = number(where, a[k + 3]);
      if (!(E > 0) || !(nu > -1 && nu < 0.5))
        throw InputError(where + ": hertz/material needs E > 0 and -1 < poisson < 0.5");
      p.kn = 4.0 / 3.0 * mix_e(E, E, nu, nu);
      normal = true, k += 4;
    } else if (w == "damping") {
      need(1, "velocity, mass_velocity, viscoelastic or tsuji");
      k = parse_granular_damping(a, k, where, p);
    } else if (w == "tangential") {
      need(1, "a tangential model");
      k = parse_granular_tangential(a, k, where, p, kt_null);
      tangential = true;
    } else if (w == "limit_damping") {
      p.limit_damping = true, ++k;
    } else if ((w == "rolling" || w == "twisting") && k + 1 < a.size() && a[k + 1] == "none") {
      k += 2;
    } else if (w == "cutoff") {
      need(1, "a distance"), number(where, a[k + 1]), k += 2;  // neighbour range only
    } else {
      throw InputError(where + ": '" + w +
                       "' is not supported (normal: hooke, hertz, "
                       "hertz/material; damping; tangential; limit_damping; rolling/twisting "
                       "none; cutoff)");
    }
  }
  if (!normal || !tangential)
    throw InputError(where + ": a granular pair_coeff needs a normal and a tangential model");
  if (kt_null) {
    if (p.normal != GranularPair::HertzMaterial)
      throw InputError(where + ": mindlin's NULL stiffness needs hertz/material (E and nu)");
    p.kt = 8 * mix_g(E, E, nu, nu);
  }
  if (p.damping == GranularPair::Tsuji) p.damp = tsuji_damping(p.damp);
  if (p.kn < 0 || p.damp < 0 || p.kt < 0 || p.xgt < 0 || p.mu < 0)
    throw InputError(where + ": coefficients must not be negative");
  p.set = true;
  return p;
}

}  // namespace

LammpsUnits lammps_units(const std::string& style) {
  LammpsUnits u;
  u.style = style;
  if (style == "lj" || style == "si" || style == "cgs" || style == "micro" || style == "nano") {
  } else if (style == "real") {
    u.ftm2v = 1.0 / 48.88821291 / 48.88821291, u.nktv2p = 68568.415;
  } else if (style == "metal") {
    u.ftm2v = 1.0 / 1.0364269e-4, u.nktv2p = 1.6021765e6;
  } else if (style == "electron") {
    u.ftm2v = 0.937582899, u.nktv2p = 2.94210108e13;
  } else {
    throw InputError("unknown LAMMPS unit style '" + style +
                     "' (lj, real, metal, si, cgs, electron, micro, nano)");
  }
  return u;
}

bool LammpsPairModel::history() const {
  if (style == LammpsStyle::GranHooke) return false;
  if (style != LammpsStyle::Granular) return true;
  return std::any_of(pairs.begin(), pairs.end(), [](const GranularPair& p) {
    return p.set && p.tangential != GranularPair::LinearNoHistory;
  });
}

std::string LammpsPairModel::describe() const {
  std::ostringstream o;
  o.precision(10);
  switch (style) {
    case LammpsStyle::GranHooke:
      o << "gran/hooke";
      break;
    case LammpsStyle::GranHookeHistory:
      o << "gran/hooke/history";
      break;
    case LammpsStyle::GranHertzHistory:
      o << "gran/hertz/history";
      break;
    case LammpsStyle::Granular:
      o << "granular";
      break;
  }
  if (style != LammpsStyle::Granular)
    o << ": kn " << kn << ", kt " << kt << ", gamma_n " << gamman << ", gamma_t " << gammat
      << ", xmu " << xmu << ", dampflag " << dampflag << (limit_damping ? ", limit_damping" : "");
  return o.str();
}

LammpsPairModel parse_lammps_pair(const std::string& pair_style,
                                  const std::vector<std::string>& pair_coeffs, int ntypes,
                                  const LammpsUnits& units) {
  LammpsPairModel m;
  m.ntypes = ntypes;
  const auto a = words(pair_style);
  const std::string where = "pair_style '" + pair_style + "'";
  if (a.empty()) throw InputError("pair_style is empty");
  if (a[0] == "gran/hooke")
    m.style = LammpsStyle::GranHooke;
  else if (a[0] == "gran/hooke/history")
    m.style = LammpsStyle::GranHookeHistory;
  else if (a[0] == "gran/hertz/history")
    m.style = LammpsStyle::GranHertzHistory;
  else if (a[0] == "granular")
    m.style = LammpsStyle::Granular;
  else
    throw InputError(where + ": style '" + a[0] +
                     "' is not one of gran/hooke, "
                     "gran/hooke/history, gran/hertz/history, granular");
  if (m.style == LammpsStyle::Granular) {
    if (a.size() > 2) throw InputError(where + ": granular takes at most a global cutoff");
    if (a.size() == 2) number(where, a[1]);  // neighbour range only
  } else {
    parse_classic(m, a, units, where);
  }
  if (pair_coeffs.empty()) throw InputError("pair_coeff: at least one line is needed");
  m.pairs.assign((ntypes + 1) * (ntypes + 1), GranularPair{});
  std::vector<bool> set((ntypes + 1) * (ntypes + 1), false);
  for (const std::string& line : pair_coeffs) {
    const auto c = words(line);
    const std::string w = "pair_coeff '" + line + "'";
    if (c.size() < 2) throw InputError(w + ": needs two type ranges");
    int ilo, ihi, jlo, jhi;
    bounds(w, c[0], ntypes, ilo, ihi);
    bounds(w, c[1], ntypes, jlo, jhi);
    GranularPair p;
    if (m.style == LammpsStyle::Granular)
      p = parse_granular_coeff(c, 2, w);
    else if (c.size() > 2)
      throw InputError(w + ": " + a[0] + " takes no per-pair coefficients");
    int count = 0;
    for (int i = ilo; i <= ihi; ++i)
      for (int j = std::max(jlo, i); j <= jhi; ++j) {
        m.pairs[i * (ntypes + 1) + j] = m.pairs[j * (ntypes + 1) + i] = p;
        set[i * (ntypes + 1) + j] = set[j * (ntypes + 1) + i] = true;
        ++count;
      }
    if (count == 0) throw InputError(w + ": sets no pair of types");
  }
  for (int i = 1; i <= ntypes; ++i)
    for (int j = i; j <= ntypes; ++j) {
      if (set[i * (ntypes + 1) + j]) continue;
      if (i == j || m.style == LammpsStyle::Granular)
        throw InputError("pair_coeff: types " + std::to_string(i) + " and " + std::to_string(j) +
                         " have no coefficients" +
                         (i == j ? std::string()
                                 : std::string("; set the pair explicitly (LAMMPS' own mixing of "
                                               "granular coefficients is not reproduced)")));
    }
  return m;
}

namespace {

// gran/hooke, gran/hooke/history, gran/hertz/history.
void classic_contact(const LammpsPairModel& m, const LammpsContactIn& c, double dt, bool update,
                     double* shear, LammpsContactOut& out) {
  const double* d = c.del;
  const double radsum = c.ri + c.rj;
  const double r = std::sqrt(c.rsq), rinv = 1.0 / r, rsqinv = 1.0 / c.rsq;
  const double vr[3] = {c.vi[0] - c.vj[0], c.vi[1] - c.vj[1], c.vi[2] - c.vj[2]};
  const double vnnr = vr[0] * d[0] + vr[1] * d[1] + vr[2] * d[2];
  double vt[3], wr[3], vtr[3], fs[3];
  for (int k = 0; k < 3; ++k) {
    vt[k] = vr[k] - d[k] * vnnr * rsqinv;
    wr[k] = (c.ri * c.wi[k] + c.rj * c.wj[k]) * rinv;
  }
  const double meff = c.mi * c.mj / (c.mi + c.mj);
  double ccel = m.kn * (radsum - r) * rinv - meff * m.gamman * vnnr * rsqinv;
  double polyhertz = 1.0;
  if (m.style == LammpsStyle::GranHertzHistory) {
    polyhertz = std::sqrt((radsum - r) * c.ri * c.rj / radsum);
    ccel *= polyhertz;
  }
  if (m.limit_damping && ccel < 0.0) ccel = 0.0;
  // Relative velocity of the surface points: v_t + (w_i a_i + w_j a_j) x n.
  vtr[0] = vt[0] - (d[2] * wr[1] - d[1] * wr[2]);
  vtr[1] = vt[1] - (d[0] * wr[2] - d[2] * wr[0]);
  vtr[2] = vt[2] - (d[1] * wr[0] - d[0] * wr[1]);
  const double vrel = std::sqrt(vtr[0] * vtr[0] + vtr[1] * vtr[1] + vtr[2] * vtr[2]);
  const double fn = m.xmu * std::fabs(ccel * r);
  if (m.style == LammpsStyle::GranHooke) {
    // Velocity damping capped by Coulomb; nothing is stored.
    const double fsm = meff * m.gammat * vrel;
    const double ft = vrel != 0.0 ? std::min(fn, fsm) / vrel : 0.0;
    for (int k = 0; k < 3; ++k) fs[k] = -ft * vtr[k];
  } else {
    if (update)
      for (int k = 0; k < 3; ++k) shear[k] += vtr[k] * dt;
    const double shrmag =
        std::sqrt(shear[0] * shear[0] + shear[1] * shear[1] + shear[2] * shear[2]);
    const double rsht = (shear[0] * d[0] + shear[1] * d[1] + shear[2] * d[2]) * rsqinv;
    if (update)  // projected into the tangent plane, its length not restored
      for (int k = 0; k < 3; ++k) shear[k] -= rsht * d[k];
    for (int k = 0; k < 3; ++k) fs[k] = -polyhertz * (m.kt * shear[k] + meff * m.gammat * vtr[k]);
    const double fsm = std::sqrt(fs[0] * fs[0] + fs[1] * fs[1] + fs[2] * fs[2]);
    if (fsm > fn) {
      if (shrmag != 0.0) {
        for (int k = 0; k < 3; ++k) {
          const double dv = meff * m.gammat * vtr[k] / m.kt;
          shear[k] = (fn / fsm) * (shear[k] + dv) - dv;
          fs[k] *= fn / fsm;
        }
      } else {
        fs[0] = fs[1] = fs[2] = 0.0;
      }
    }
  }
  for (int k = 0; k < 3; ++k) out.f[k] = d[k] * ccel + fs[k];
  const double tor[3] = {rinv * (d[1] * fs[2] - d[2] * fs[1]), rinv * (d[2] * fs[0] - d[0] * fs[2]),
                         rinv * (d[0] * fs[1] - d[1] * fs[0])};
  for (int k = 0; k < 3; ++k) out.torque_i[k] = -c.ri * tor[k], out.torque_j[k] = -c.rj * tor[k];
}

// pair_style granular.
void granular_contact(const GranularPair& p, const LammpsContactIn& c, double dt, bool update,
                      double* h, LammpsContactOut& out) {
  const double radsum = c.ri + c.rj;
  const double r = std::sqrt(c.rsq), rinv = 1.0 / r;
  const double n[3] = {c.del[0] * rinv, c.del[1] * rinv, c.del[2] * rinv};
  const double vr[3] = {c.vi[0] - c.vj[0], c.vi[1] - c.vj[1], c.vi[2] - c.vj[2]};
  const double vnnr = vr[0] * n[0] + vr[1] * n[1] + vr[2] * n[2];
  const double meff = c.mi * c.mj / (c.mi + c.mj);
  const double delta = radsum - r;
  const double reff = c.ri * c.rj / radsum;
  const double a = std::sqrt(delta * reff);
  double knfac = p.kn, fne = knfac * delta;
  if (p.normal != GranularPair::Hooke) fne *= a, knfac *= a;
  double damp_normal = 0;
  switch (p.damping) {
    case GranularPair::Velocity:
      damp_normal = 1;
      break;
    case GranularPair::MassVelocity:
      damp_normal = meff;
      break;
    case GranularPair::Viscoelastic:
      damp_normal = a * meff;
      break;  // also for hooke
    case GranularPair::Tsuji:
      damp_normal = std::sqrt(meff * knfac);
      break;
  }
  const double prefactor = p.damp * damp_normal;
  double fntot = fne - prefactor * vnnr;
  if (p.limit_damping && fntot < 0.0) fntot = 0.0;
  double wr[3], vtr[3], fs[3];
  for (int k = 0; k < 3; ++k) wr[k] = c.ri * c.wi[k] + c.rj * c.wj[k];
  vtr[0] = vr[0] - n[0] * vnnr - (n[2] * wr[1] - n[1] * wr[2]);
  vtr[1] = vr[1] - n[1] * vnnr - (n[0] * wr[2] - n[2] * wr[0]);
  vtr[2] = vr[2] - n[2] * vnnr - (n[1] * wr[0] - n[0] * wr[1]);
  const double vrel = std::sqrt(vtr[0] * vtr[0] + vtr[1] * vtr[1] + vtr[2] * vtr[2]);
  const double fscrit = p.mu * std::fabs(fntot);
  const double damp_t = p.xgt * prefactor;
  if (p.tangential == GranularPair::LinearNoHistory) {
    const double fsm = damp_t * vrel;
    const double ft = vrel != 0.0 ? std::min(fscrit, fsm) / vrel : 0.0;
    for (int k = 0; k < 3; ++k) fs[k] = -ft * vtr[k];
  } else {
    const double kt = p.tangential == GranularPair::Mindlin ? p.kt * a : p.kt;
    if (update) {
      // Rotated into the tangent plane with its length kept, only when it has left the
      // plane by more than a tiny fraction of the sliding limit; then advanced.
      const double rsht = h[0] * n[0] + h[1] * n[1] + h[2] * n[2];
      if (std::fabs(rsht) * kt > 1e-10 * fscrit) {
        const double shrmag = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        for (int k = 0; k < 3; ++k) h[k] -= rsht * n[k];
        const double prjmag = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        const double scale = prjmag > 0 ? shrmag / prjmag : 0;
        for (int k = 0; k < 3; ++k) h[k] *= scale;
      }
      for (int k = 0; k < 3; ++k) h[k] += vtr[k] * dt;
    }
    for (int k = 0; k < 3; ++k) fs[k] = -kt * h[k] - damp_t * vtr[k];
    const double fsm = std::sqrt(fs[0] * fs[0] + fs[1] * fs[1] + fs[2] * fs[2]);
    if (fsm > fscrit) {
      const double shrmag = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
      if (shrmag != 0.0) {
        for (int k = 0; k < 3; ++k) {
          h[k] = -1.0 / kt * (fscrit * fs[k] / fsm + damp_t * vtr[k]);
          fs[k] *= fscrit / fsm;
        }
      } else {
        fs[0] = fs[1] = fs[2] = 0.0;
      }
    }
  }
  for (int k = 0; k < 3; ++k) out.f[k] = n[k] * fntot + fs[k];
  const double tor[3] = {n[1] * fs[2] - n[2] * fs[1], n[2] * fs[0] - n[0] * fs[2],
                         n[0] * fs[1] - n[1] * fs[0]};
  // Lever arms to the middle of the overlap.
  const double li = c.ri - 0.5 * delta, lj = c.rj - 0.5 * delta;
  for (int k = 0; k < 3; ++k) out.torque_i[k] = -li * tor[k], out.torque_j[k] = -lj * tor[k];
}

}  // namespace

void lammps_contact(const LammpsPairModel& m, const LammpsContactIn& c, double dt, bool update,
                    double* history, LammpsContactOut& out) {
  if (m.style == LammpsStyle::Granular)
    granular_contact(m.pair(c.ti, c.tj), c, dt, update, history, out);
  else
    classic_contact(m, c, dt, update, history, out);
}

}  // namespace granular
