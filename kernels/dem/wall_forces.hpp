// Sphere-wall contacts and body forces. A wall is evaluated by the same contact model
// structs as a pair, as a partner of infinite radius and mass (PairState::wall): R* = a_i,
// m* = m_i, the wall's material in its species slot. Every particle tests every wall
// (walls are few), so wall contacts need no list; their history is a dense
// (particle, wall) table that moves with the particles when they are reordered. Multi-contact
// laws act through a hook, as in the pair pass.
#pragma once
#include <Kokkos_Core.hpp>
#include <cmath>
#include <vector>

#include "core/dem/particles.hpp"
#include "core/dem/walls.hpp"
#include "kernels/contact/contact_model.hpp"
#include "kernels/dem/contact_forces.hpp"
#include "kernels/dem/deterministic_sum.hpp"
#include "kernels/dem/wall_record.hpp"

namespace granular {

// The overlap a + gap of a sphere (centre x, radius a) with wall w, the gap being the signed
// distance along the wall's outward normal (negative inside): the sphere touches where it is
// positive.
KOKKOS_INLINE_FUNCTION double wall_overlap(const double x[3], double a, const Wall& w) {
  const double gap = (x[0] - w.p[0]) * w.n[0] + (x[1] - w.p[1]) * w.n[1] + (x[2] - w.p[2]) * w.n[2];
  return a + gap;
}

// Geometry and relative motion of particle bi against wall w; false if they do not touch.
// The normal points from the wall into the particle (the direction of the force on it).
KOKKOS_INLINE_FUNCTION bool wall_geometry(const Body& bi, const Wall& w, bool rotations,
                                          PairState& s) {
  const double delta = wall_overlap(bi.x, bi.a, w);
  if (!(delta > 0.0)) return false;
  s.n[0] = -w.n[0], s.n[1] = -w.n[1], s.n[2] = -w.n[2];
  s.delta = delta;
  s.ai = bi.a, s.aj = 0.0;
  s.mstar = bi.m;
  s.si = bi.s, s.sj = w.material;
  s.wall = true;
  const double dv[3] = {bi.v[0] - w.v[0], bi.v[1] - w.v[1], bi.v[2] - w.v[2]};
  const double vn = dot3(dv, s.n);
  s.delta_dot = -vn;
  // Contact point mid-overlap, as for pairs: lever arm a_i - delta/2 from the centre.
  const double li = bi.a - 0.5 * delta;
  double c[3] = {0, 0, 0};
  if (rotations) {
    const double aw[3] = {li * bi.w[0], li * bi.w[1], li * bi.w[2]};
    cross3(aw, s.n, c);
  }
  for (int d = 0; d < 3; ++d) {
    s.vt[d] = dv[d] - vn * s.n[d] - c[d];
    s.wrel[d] = rotations ? bi.w[d] : 0.0;
  }
  return true;
}

// Extension point for laws that need more than the contact (multi-contact,
// kernels/dem/multicontact.hpp): a hook may replace the evaluation of a touching sphere-wall
// contact and record per-contact data. NoWallHook compiles the classical kernel unchanged.
struct NoWallHook {
  static constexpr bool active = false;
  static constexpr const char* label = "dem::add_external_forces";
  template <class Model>
  KOKKOS_INLINE_FUNCTION void evaluate(const Model&, int, int, const PairState&, double, double*,
                                       PairForce&) const {}
  KOKKOS_INLINE_FUNCTION void apart(int, int) const {}
};

// The wall pass over one particle: adds its wall contact forces and gravity to f and torque,
// advances its wall histories and gives each wall contact's share to the sink (WallRowSink or
// WallBlockSink, kernels/dem/wall_record.hpp). A functor class rather than a lambda: nvcc's
// wrapper of a host-device lambda inside a function template instantiated in several
// translation units can be linked with a null copy helper, and the walls' tests then jumped to
// address 0 on a device (docs/perf_design_notes.md, GPU).
template <class ExecSpace, class Model, class HistoryView, class Hook>
struct WallForcePass {
  ParticleViews<ExecSpace> pv;
  typename Particles<ExecSpace>::vec_view f, torque;
  typename WallSet<ExecSpace>::view_type walls;
  int nwalls;
  HistoryView history;
  WallTouchView<ExecSpace> touch;
  Model m;
  Hook hook;
  double g[3];
  bool weightless;  // g is (+0, +0, +0): m g is +0 for any particle, its mass is not read
  double dt;

  template <class Sink>
  KOKKOS_INLINE_FUNCTION void particle(const int i, const Sink& sink) const {
    constexpr int H = Model::history;
    constexpr bool rot = Model::rotations;
    // Position and radius tell whether a wall touches; the rest of the particle is loaded
    // for its first contact only (most particles touch no wall).
    const double x[3] = {pv.x(i, 0), pv.x(i, 1), pv.x(i, 2)};
    const double a = pv.radius(i);
    Body bi{};
    bool loaded = false;
    double fi[3] = {0.0, 0.0, 0.0};
    if (!weightless) {
      const double mi = pv.mass(i);
      for (int d = 0; d < 3; ++d) fi[d] = mi * g[d];
    }
    double qi[3] = {0, 0, 0};
    for (int w = 0; w < nwalls; ++w) {
      const Wall& wall = walls(w);  // a reference: a copy on the stack stalled every load of it
      if (!(wall_overlap(x, a, wall) > 0.0)) {  // wall_geometry's own test
        // Its share and history are already zero unless the contact just ended (the flag
        // says so): rewriting them every step cost more memory traffic than the contacts.
        if (touch(i, w) != 0) {
          sink.ended(i, w);
          if constexpr (H > 0)
            for (int c = 0; c < H; ++c) history(i, w * H + c) = 0.0;  // contact forgotten
        }
        if constexpr (Hook::active) hook.apart(i, w);
        continue;
      }
      if (!loaded) bi = load_body(pv, i, rot), loaded = true;
      PairState s;
      if (!wall_geometry(bi, wall, rot, s)) continue;  // never: the test above, the same numbers
      double h[H > 0 ? H : 1];
      if constexpr (H > 0)
        for (int c = 0; c < H; ++c) h[c] = history(i, w * H + c);
      PairForce out;
      if constexpr (Hook::active)
        hook.evaluate(m, i, w, s, dt, h, out);
      else
        m.evaluate(s, dt, h, out);
      if constexpr (H > 0)
        for (int c = 0; c < H; ++c) history(i, w * H + c) = h[c];
      for (int d = 0; d < 3; ++d) fi[d] += out.f[d];
      if constexpr (rot)
        for (int d = 0; d < 3; ++d) qi[d] += out.q[d];
      // Reaction on the wall: force -f and, about the wall point p, the torque that
      // balances the particle's angular momentum change: -(x_i - p) x f - q_i.
      const double r[3] = {bi.x[0] - wall.p[0], bi.x[1] - wall.p[1], bi.x[2] - wall.p[2]};
      double rxf[3];
      cross3(r, out.f, rxf);
      double share[kWallColumns];
      for (int d = 0; d < 3; ++d) {
        share[d] = -out.f[d];
        share[3 + d] = -rxf[d] - (rot ? out.q[d] : 0.0);
      }
      share[6] = 1.0;
      share[7] = m.energy(s, h);
      share[8] = s.delta / s.ai;
      sink.contact(i, w, share);
    }
    for (int d = 0; d < 3; ++d) f(i, d) += fi[d];
    if constexpr (rot)
      for (int d = 0; d < 3; ++d) torque(i, d) += qi[d];
  }
};

// One thread per particle, each contact's share to the particle's row.
template <class Pass, class ExecSpace>
struct WallRowsDriver {
  Pass pass;
  WallRowSink<ExecSpace> sink;
  KOKKOS_INLINE_FUNCTION void operator()(const int i) const { pass.particle(i, sink); }
};

// One thread per block of kDeterministicBlock particles, visited in order, each contact's
// share added to the block's sums.
template <class Pass, class ExecSpace>
struct WallBlocksDriver {
  Pass pass;
  typename WallRecord<ExecSpace>::sums_view sums;
  int n, columns;
  KOKKOS_INLINE_FUNCTION void operator()(const int b) const {
    double* row = columns > 0 ? &sums(b, 0) : nullptr;
    for (int c = 0; c < columns; ++c) row[c] = 0.0;
    const WallBlockSink<ExecSpace> sink{row, pass.touch};
    const int begin = b * kDeterministicBlock;
    const int end = begin + kDeterministicBlock < n ? begin + kDeterministicBlock : n;
    for (int i = begin; i < end; ++i) pass.particle(i, sink);
  }
};

// Adds wall contact forces and gravity to f and torque (after the pair gather), advances
// the wall histories (n, walls * H), and records what each wall feels (`record`, its layout
// by blocks or by rows).
template <class ExecSpace, class Model, class HistoryView, class Hook = NoWallHook>
void add_external_forces(const Particles<ExecSpace>& p,
                         const typename WallSet<ExecSpace>::view_type& walls, int nwalls,
                         const HistoryView& history, WallRecord<ExecSpace>& record,
                         const Model& model, const double gravity[3], double dt,
                         const Hook& wall_hook = Hook()) {
  bool weightless = true;
  for (int d = 0; d < 3; ++d)
    weightless = weightless && gravity[d] == 0.0 && !std::signbit(gravity[d]);
  using Pass = WallForcePass<ExecSpace, Model, HistoryView, Hook>;
  const Pass pass{ParticleViews<ExecSpace>(p),
                  p.f,
                  p.torque,
                  walls,
                  nwalls,
                  history,
                  record.touch(),
                  model,
                  wall_hook,
                  {gravity[0], gravity[1], gravity[2]},
                  weightless,
                  dt};
  if (record.by_blocks()) {
    const int blocks = (p.n + kDeterministicBlock - 1) / kDeterministicBlock;
    Kokkos::parallel_for(
        Hook::label, Kokkos::RangePolicy<ExecSpace>(0, blocks),
        WallBlocksDriver<Pass, ExecSpace>{pass, record.block_sums_view(), p.n,
                                          record.walls() > 0 ? nwalls * kWallColumns : 0});
  } else {
    Kokkos::parallel_for(Hook::label, Kokkos::RangePolicy<ExecSpace>(0, p.n),
                         WallRowsDriver<Pass, ExecSpace>{pass, record.row_sink()});
  }
  record.evaluated();
}

}  // namespace granular
