// The particles a mixture study starts from: its own gas, or another tool's packing.
//
// mixture_gas: the same sizes and positions for every soft fraction (the same seed), the soft
// material given to exactly round(nu N) particles chosen by a random permutation derived from
// the seed (equal size distributions, so number and volume fractions agree).
//
// mixture_from_file: particles.from (a LAMMPS data file, the last frame of an H5MD series, or
// the state group particles.from_group of an .h5 file, read_scene_packing) with
// particles.from_materials naming the material of the file's species 0, 1, ... (LAMMPS
// types 1, 2, ...); each must be the mixture's stiff or soft material, whose density every
// particle then takes (the materials define the densities, as for a generated gas).
#pragma once
#include "core/dem/box.hpp"
#include "core/dem/host_particles.hpp"
#include "core/io/scene_file.hpp"
#include "scenarios/common/packing.hpp"
#include "scenarios/waves/mixture_materials.hpp"

namespace granular {

HostParticles mixture_gas(const GasSpec& gas, const MixtureMaterials& mats, int stiff, int soft,
                          double soft_fraction, PeriodicBox& box);

HostParticles mixture_from_file(const SceneFile& scene, const MixtureMaterials& mats, int stiff,
                                int soft, PeriodicBox& box);

// The volume fraction of the particles of species `soft` among all particles.
double soft_volume_fraction(const HostParticles& h, int soft);

}  // namespace granular
