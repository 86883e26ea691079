// LAMMPS force reference (see lammps_forces.hpp).
#include "core/lammps/lammps_forces.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/run/error.hpp"

namespace granular {

namespace {
void cross(const double a[3], const double b[3], double c[3]) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
std::uint64_t pair_key(int i, int j) {
  return (static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint32_t>(j);
}
}  // namespace

double LammpsBox::width(int d) const {
  double c[3];
  cross(edge[(d + 1) % 3], edge[(d + 2) % 3], c);
  return volume() / std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
}

void LammpsBox::fractional(const double d[3], double s[3]) const {
  s[2] = d[2] / edge[2][2];
  s[1] = (d[1] - edge[2][1] * s[2]) / edge[1][1];
  s[0] = (d[0] - edge[1][0] * s[1] - edge[2][0] * s[2]) / edge[0][0];
}

LammpsForceField::LammpsForceField(const LammpsData& data, LammpsPairModel model, LammpsUnits units,
                                   double dt)
    : model_(std::move(model)), units_(std::move(units)), dt_(dt) {
  const HostParticles& h = data.particles;
  const int n = h.size();
  for (int d = 0; d < 3; ++d) box.lo[d] = data.lo[d];
  box.edge[0][0] = data.len[0];
  box.edge[1][0] = data.tilt[0], box.edge[1][1] = data.len[1];
  box.edge[2][0] = data.tilt[1], box.edge[2][1] = data.tilt[2], box.edge[2][2] = data.len[2];
  id = data.ids;
  type.resize(n), radius.resize(n), mass.resize(n);
  x.resize(3 * n), v.resize(3 * n), omega.resize(3 * n), force.assign(3 * n, 0.0);
  torque.assign(3 * n, 0.0);
  double rmax = 0;
  for (int i = 0; i < n; ++i) {
    type[i] = h.species[i] + 1;
    radius[i] = h.radius[i];
    // LAMMPS' atom style sphere: mass = density * 4/3 pi a^3, in this order of operations.
    mass[i] = h.density[i] * (4.0 * M_PI / 3.0 * radius[i] * radius[i] * radius[i]);
    x[3 * i] = h.x[i], x[3 * i + 1] = h.y[i], x[3 * i + 2] = h.z[i];
    v[3 * i] = h.vx[i], v[3 * i + 1] = h.vy[i], v[3 * i + 2] = h.vz[i];
    omega[3 * i] = h.wx[i], omega[3 * i + 1] = h.wy[i], omega[3 * i + 2] = h.wz[i];
    rmax = std::max(rmax, radius[i]);
  }
  cut_ = 2 * rmax;
  for (int d = 0; d < 3; ++d)
    if (!(box.width(d) > cut_)) {
      std::ostringstream o;
      o << "the periodic box is " << box.width(d) << " wide across edge "
        << "abc"[d] << ", not more than the largest contact distance " << cut_
        << ": a particle would touch its own image; use a larger box";
      throw InputError(o.str());
    }
  if (!(dt > 0)) throw InputError("the time step must be positive");
}

double LammpsForceField::kinetic_energy() const {
  double e = 0;
  for (int i = 0; i < size(); ++i)
    e += 0.5 * mass[i] *
         (v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]);
  return e * (1.0 / units_.ftm2v);  // mvv2e = 1/ftm2v for every unit style here
}

namespace {
// Atoms binned in fractional coordinates, each bin at least one contact distance thick across:
// partners in contact sit in the same or adjacent bins (periodically).
struct AtomBins {
  int nb[3];
  std::vector<int> bin_of, members;  // each atom's bin; the atoms bin by bin
  std::vector<long> start;           // where each bin's atoms begin in members

  AtomBins(const LammpsBox& box, const std::vector<double>& x, double cut) {
    const int n = static_cast<int>(x.size() / 3);
    for (int d = 0; d < 3; ++d) nb[d] = std::max(1, static_cast<int>(box.width(d) / cut));
    const long nbins = static_cast<long>(nb[0]) * nb[1] * nb[2];
    bin_of.resize(n);
    start.assign(nbins + 1, 0);
    for (int i = 0; i < n; ++i) {
      double d[3] = {x[3 * i] - box.lo[0], x[3 * i + 1] - box.lo[1], x[3 * i + 2] - box.lo[2]},
             s[3];
      box.fractional(d, s);
      int b[3];
      for (int k = 0; k < 3; ++k) {
        const double f = s[k] - std::floor(s[k]);
        b[k] = std::min(nb[k] - 1, static_cast<int>(f * nb[k]));
      }
      bin_of[i] = (b[2] * nb[1] + b[1]) * nb[0] + b[0];
      ++start[bin_of[i] + 1];
    }
    for (long b = 0; b < nbins; ++b) start[b + 1] += start[b];
    members.resize(n);
    std::vector<long> fill(start.begin(), start.end() - 1);
    for (int i = 0; i < n; ++i) members[fill[bin_of[i]]++] = i;
  }

  // Bin b and its neighbours, each once (a box of fewer than three bins across repeats them).
  void around(int b, std::vector<long>& near) const {
    const int bx = b % nb[0], by = (b / nb[0]) % nb[1], bz = b / (nb[0] * nb[1]);
    near.clear();
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int cx = (bx + dx + nb[0]) % nb[0], cy = (by + dy + nb[1]) % nb[1],
                    cz = (bz + dz + nb[2]) % nb[2];
          near.push_back((static_cast<long>(cz) * nb[1] + cy) * nb[0] + cx);
        }
    std::sort(near.begin(), near.end());
    near.erase(std::unique(near.begin(), near.end()), near.end());
  }
};

// The periodic images of d0 = x_i - x_j around the nearest lattice shift that lie closer than
// radsum: how many, and (for one) its separation del and squared length rsq.
int touching_images(const LammpsBox& box, const double d0[3], double radsum, double del[3],
                    double& rsq) {
  double s[3];
  box.fractional(d0, s);
  double base[3];
  for (int k = 0; k < 3; ++k) base[k] = std::nearbyint(s[k]);
  int touching = 0;
  for (int kc = -1; kc <= 1; ++kc)
    for (int kb = -1; kb <= 1; ++kb)
      for (int ka = -1; ka <= 1; ++ka) {
        const double sh[3] = {base[0] + ka, base[1] + kb, base[2] + kc};
        double e[3];
        for (int k = 0; k < 3; ++k)
          e[k] = d0[k] - (sh[0] * box.edge[0][k] + sh[1] * box.edge[1][k] + sh[2] * box.edge[2][k]);
        const double r2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        if (r2 < radsum * radsum) {
          ++touching;
          for (int k = 0; k < 3; ++k) del[k] = e[k];
          rsq = r2;
        }
      }
  return touching;
}
}  // namespace

void LammpsForceField::compute(bool update) {
  const int n = size();
  std::fill(force.begin(), force.end(), 0.0);
  std::fill(torque.begin(), torque.end(), 0.0);
  virial.fill(0.0);
  contacts = 0;
  const AtomBins bins(box, x, cut_);
  std::unordered_map<std::uint64_t, std::array<double, 3>> next;
  std::vector<long> near;
  for (int i = 0; i < n; ++i) {
    bins.around(bins.bin_of[i], near);
    for (long c : near)
      for (long m = bins.start[c]; m < bins.start[c + 1]; ++m) {
        const int j = bins.members[m];
        if (j <= i) continue;
        const double d0[3] = {x[3 * i] - x[3 * j], x[3 * i + 1] - x[3 * j + 1],
                              x[3 * i + 2] - x[3 * j + 2]};
        // The images around the nearest lattice shift; at most one may touch.
        double del[3] = {0, 0, 0}, rsq = 0;
        const int touching = touching_images(box, d0, radius[i] + radius[j], del, rsq);
        if (touching == 0) continue;
        if (touching > 1)
          throw InputError("atoms " + std::to_string(id[i]) + " and " + std::to_string(id[j]) +
                           " touch through two periodic images: the box is too small");
        add_contact(i, j, del, rsq, update, next);
      }
  }
  // A contact that ended leaves no history behind.
  history_.swap(next);
}

void LammpsForceField::add_contact(int i, int j, const double del[3], double rsq, bool update,
                                   std::unordered_map<std::uint64_t, std::array<double, 3>>& next) {
  std::array<double, 3> hist{0, 0, 0};
  if (model_.history()) {
    auto it = history_.find(pair_key(i, j));
    if (it != history_.end()) hist = it->second;
  }
  LammpsContactIn in{{del[0], del[1], del[2]},
                     rsq,
                     &v[3 * i],
                     &v[3 * j],
                     &omega[3 * i],
                     &omega[3 * j],
                     radius[i],
                     radius[j],
                     mass[i],
                     mass[j],
                     type[i],
                     type[j]};
  LammpsContactOut out;
  lammps_contact(model_, in, dt_, update, hist.data(), out);
  if (model_.history()) next[pair_key(i, j)] = hist;
  for (int k = 0; k < 3; ++k) {
    force[3 * i + k] += out.f[k], force[3 * j + k] -= out.f[k];
    torque[3 * i + k] += out.torque_i[k], torque[3 * j + k] += out.torque_j[k];
  }
  virial[0] += del[0] * out.f[0], virial[1] += del[1] * out.f[1];
  virial[2] += del[2] * out.f[2], virial[3] += del[0] * out.f[1];
  virial[4] += del[0] * out.f[2], virial[5] += del[1] * out.f[2];
  ++contacts;
}

void LammpsForceField::step() {
  const int n = size();
  const double dtf = 0.5 * dt_ * units_.ftm2v, dtfrot = dtf / 0.4;
  auto kick = [&] {
    for (int i = 0; i < n; ++i) {
      const double dtfm = dtf / mass[i];
      const double dtirot = dtfrot / (radius[i] * radius[i] * mass[i]);
      for (int k = 0; k < 3; ++k) {
        v[3 * i + k] += dtfm * force[3 * i + k];
        omega[3 * i + k] += dtirot * torque[3 * i + k];
      }
    }
  };
  kick();
  for (int i = 0; i < 3 * n; ++i) x[i] += dt_ * v[i];
  // A time step far too large sends atoms to infinity; the binning cannot place them.
  for (int i = 0; i < 3 * n; ++i)
    if (!std::isfinite(x[i]))
      throw PhysicsError("atom " + std::to_string(i / 3 + 1) + " left to a non-finite position " +
                         "at step " + std::to_string(steps_done + 1) + ": the time step is far " +
                         "too large (lammps.timestep)");
  compute(true);
  kick();
  ++steps_done;
}

}  // namespace granular
