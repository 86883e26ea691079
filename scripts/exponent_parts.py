#!/usr/bin/python3
"""Splits the exponent n of M ∝ P^n of a mixture_moduli run into the part a fixed contact
network gives and the part of the contacts the pressure adds (docs/guide_waves.md, "What
sets the exponent").

    scripts/exponent_parts.py RESULTS.h5 [RESULTS.h5 ...] [--out TABLE.md]

For Hertz contacts the normal stiffness of a contact grows as its force to the 1/3, so an
affine (effective-medium) modulus is M_aff ∝ c k̄ with c = φ Z̄ the contacts per volume (in
particle volumes, up to a constant) and k̄ ∝ (P/c)^(1/3): M_aff ∝ c^(2/3) P^(1/3). Its
exponent is n_aff = 1/3 + (2/3) n_c, n_c the exponent of c against P: 1/3 for a network that
keeps its contacts, more where the pressure adds contacts. What the measured n has beyond
n_aff is the non-affine part: the relaxation of a network near isostaticity, which weakens
as the pressure adds contacts. In a mixture the load also moves between contact types: where
the run measured its skeleton (`[analysis] skeleton = true`), n_types is the exponent of
Σ_t c_t^(2/3) (E*_t² s_t P)^(1/3) over the glass–glass, glass–rubber and rubber–rubber
contacts, c_t their number per volume and s_t their share of the pressure (the same affine
estimate summed by type, E*_t from the materials in the run's summary.json). Every slope is a least-squares fit in log-log over the
probed states of one mixture (the rule of `contact.pair_rule`; the other rule's sample is
left out), with its standard error where there are more than two points.
"""
import argparse
import json
import math
import sys
from pathlib import Path

import h5py
import numpy as np


def slope(x, y):
    """Least-squares slope of log y against log x and its standard error (NaN with two points)."""
    lx, ly = np.log(x), np.log(y)
    a = np.vstack([lx, np.ones_like(lx)]).T
    coef = np.linalg.lstsq(a, ly, rcond=None)[0]
    n = len(x)
    if n <= 2:
        return coef[0], math.nan
    resid = ly - a @ coef
    s2 = float(resid @ resid) / (n - 2)
    var = s2 / float(((lx - lx.mean()) ** 2).sum())
    return coef[0], math.sqrt(var)


def fmt(v, e=math.nan):
    if math.isnan(v):
        return "—"
    return f"{v:.3f}" if math.isnan(e) else f"{v:.3f} ± {e:.3f}"


def plane_modulus(params, name):
    """E/(1 - nu^2) of a material of the run (E from young_modulus or shear_modulus)."""
    nu = params[f"materials.{name}.poisson"]
    e = params.get(f"materials.{name}.young_modulus")
    if e is None:
        e = 2 * params[f"materials.{name}.shear_modulus"] * (1 + nu)
    return e / (1 - nu * nu)


def type_stiffness(path):
    """E* of glass-glass, glass-rubber and rubber-rubber contacts, or None without a summary."""
    summary = Path(path).with_name("summary.json")
    if not summary.exists():
        return None
    params = json.loads(summary.read_text())["parameters"]
    hard = plane_modulus(params, params["mixture.stiff_material"])
    soft = plane_modulus(params, params["mixture.soft_material"])
    return (hard / 2, 1 / (1 / hard + 1 / soft), soft / 2)


def n_by_type(t, sel, nu, e_star):
    """Exponent of the affine modulus summed by contact type (NaN without skeleton columns)."""
    if e_star is None or "skeleton_share_stiff_stiff" not in t:
        return math.nan
    def col(name):
        return np.nan_to_num(t[name][sel])
    per_particle = [(1 - nu) * col("skeleton_z_stiff_stiff") / 2,
                    (1 - nu) * col("skeleton_z_stiff_soft"),
                    nu * col("skeleton_z_soft_soft") / 2]
    shares = [col("skeleton_share_stiff_stiff"), col("skeleton_share_stiff_soft"),
              col("skeleton_share_soft_soft")]
    p, phi = t["pressure"][sel], t["phi"][sel]
    m = sum((phi * z) ** (2 / 3) * (e * e * sh * p) ** (1 / 3)
            for z, sh, e in zip(per_particle, shares, e_star))
    return slope(p, m)[0]


def rows_of(path):
    with h5py.File(path, "r") as f:
        t = {k: f["table"][k][()] for k in f["table"].keys()}
    e_star = type_stiffness(path)
    other = t.get("pair_rule_product_over_sum", np.zeros_like(t["M"]))
    # The scene's own rule is the one every mixture has; the pair-rule check adds the other
    # rule for one mixture only.
    rules = {r: len({float(x) for x, o in zip(t["soft_fraction"], other) if o == r})
             for r in set(other.tolist())}
    rule = max(rules, key=rules.get)
    out = []
    for nu in sorted({float(x) for x in t["soft_fraction"]}):
        sel = ((t["soft_fraction"] == nu) & (other == rule) & (t["probed"] == 1)
               & np.isfinite(t["M"]))
        if sel.sum() < 2:
            out.append((nu, int(sel.sum())) + (math.nan,) * 11)
            continue
        p = t["pressure"][sel]
        c = t["phi"][sel] * t["z_mean"][sel]
        n_m, e_m = slope(p, t["M"][sel])
        n_k, e_k = slope(p, t["K"][sel])
        n_g, e_g = slope(p, t["G"][sel])
        n_c, e_c = slope(p, c)
        n_aff = 1 / 3 + 2 / 3 * n_c
        out.append((nu, int(sel.sum()), n_m, e_m, n_k, n_g, n_c, e_c, n_aff, n_m - n_aff,
                    float(t["z_mean"][sel][0]), float(t["z_mean"][sel][-1]),
                    n_by_type(t, sel, nu, e_star)))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", nargs="+")
    ap.add_argument("--out")
    args = ap.parse_args()
    lines = []
    for path in args.results:
        lines += [f"`{path}`", "",
                  "| ν_r | states | n (M) | n (K) | n (G) | n_c of φZ̄ | Z̄ first → last | "
                  "n_aff = 1/3 + 2n_c/3 | n − n_aff (non-affine) | n_types |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for r in rows_of(path):
            nu, k = r[0], r[1]
            if math.isnan(r[2]):
                lines.append(f"| {nu:g} | {k} | — | — | — | — | — | — | — | — |")
                continue
            _, _, n_m, e_m, n_k, n_g, n_c, e_c, n_aff, rest, z0, z1, n_t = r
            lines.append(f"| {nu:g} | {k} | {fmt(n_m, e_m)} | {fmt(n_k)} | {fmt(n_g)} | "
                         f"{fmt(n_c, e_c)} | {z0:.2f} → {z1:.2f} | {fmt(n_aff)} | {fmt(rest)} | "
                         f"{fmt(n_t)} |")
        lines.append("")
    text = "\n".join(lines)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")
    sys.stdout.write(text + "\n")


if __name__ == "__main__":
    main()
