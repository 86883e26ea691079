"""Charts of the isotropic_compression scene: P*(phi), Z(phi), E_kin/E_pot(phi)."""
import sys

import h5py
import numpy as np

from chartkit import plt, save

h5, outdir = sys.argv[1], sys.argv[2]
with h5py.File(h5, "r") as f:
    s = {k: f["series"][k][:] for k in f["series"]}
comp = s["phase"] == 0
phi = s["phi"]

fig, ax = plt.subplots(figsize=(5.5, 4))
ok = comp & (s["pressure_star"] > 0)
ax.semilogy(phi[ok], s["pressure_star"][ok], lw=1.2)
ax.set_xlabel("volume fraction phi")
ax.set_ylabel("P* = P <d> / k_n")
ax.set_title("Pressure during isotropic compression")
save(fig, outdir, "pressure_vs_phi.png")

fig, ax = plt.subplots(figsize=(5.5, 4))
ax.plot(phi[comp], s["z"][comp], label="Z (all particles)")
ax.plot(phi[comp], s["z_corrected"][comp], label="Z corrected (non-rattlers)")
ax.axhline(6, color="k", ls=":", lw=0.8, label="isostatic, frictionless")
ax.set_xlabel("volume fraction phi")
ax.set_ylabel("coordination number")
ax.legend()
ax.set_title("Coordination during isotropic compression")
save(fig, outdir, "coordination_vs_phi.png")

fig, ax = plt.subplots(figsize=(5.5, 4))
r = s["ekin_over_epot"]
ok = comp & np.isfinite(r) & (r > 0)
ax.semilogy(phi[ok], r[ok])
ax.set_xlabel("volume fraction phi")
ax.set_ylabel("E_kin / E_pot")
ax.set_title("Kinetic over elastic energy")
save(fig, outdir, "energy_ratio_vs_phi.png")
