// The run-time choice of contact law and the packings of the library API (simulation.hpp).
#include "scenarios/api/simulation.hpp"

#include <atomic>
#include <cmath>

#include "core/io/output.hpp"
#include "core/io/scene_file.hpp"
#include "core/lammps/lammps_data.hpp"
#include "scenarios/common/contact_config.hpp"
#include "scenarios/common/dem_output.hpp"
#include "scenarios/common/materials.hpp"
#include "scenarios/common/packing.hpp"

namespace granular::api {

namespace {

std::atomic<int> g_alive{0};

using Exec = Kokkos::DefaultExecutionSpace;

void require(bool ok, const std::string& what) {
  if (!ok) throw InputError(what);
}

// Builds the simulation for the contact law of `contact` (see make_simulation).
std::unique_ptr<Simulation> build(const std::string& contact, const std::string& source,
                                  const DemParams& params, HostParticles host,
                                  std::vector<double> w, const PeriodicBox& box,
                                  const ConfigState* history) {
  const SceneFile scene = SceneFile::parse(contact, source);
  std::unique_ptr<Simulation> out;
  int species_slots = kMaxSpecies;
  std::string name;
  auto check_species = [&] {
    for (int i = 0; i < host.size(); ++i)
      if (host.species[i] < 0 || host.species[i] >= species_slots)
        throw InputError(source + ": particle " + std::to_string(i) + " has species " +
                         std::to_string(host.species[i]) + ", which names no material (" +
                         std::to_string(species_slots) + " in the contact law)");
  };
  auto make = [&](const auto& model) {
    check_species();
    Particles<Exec> p = Particles<Exec>::from_host(host);
    if (!w.empty()) {  // a saved state's spins, in identity order as the particles
      auto wh = Kokkos::create_mirror_view(p.w);
      for (int i = 0; i < p.n; ++i)
        for (int d = 0; d < 3; ++d) wh(i, d) = w[3 * static_cast<size_t>(i) + d];
      Kokkos::deep_copy(p.w, wh);
    }
    out = simulation_of(model, name, std::move(p), host.density, box, params, history);
  };
  if (!scene.tables("materials").empty()) {
    const MaterialSet m = MaterialSet::read(scene);
    scene.reject_unknown_keys();
    species_slots = static_cast<int>(m.materials.size());
    // A material with a density gives it to its particles; one without keeps theirs.
    for (int i = 0; i < host.size(); ++i) {
      const int s = host.species[i];
      if (s >= 0 && s < species_slots && m.materials[static_cast<size_t>(s)].density > 0)
        host.density[i] = m.materials[static_cast<size_t>(s)].density;
    }
    name = m.tangential ? "materials+mindlin" : "materials";
    with_material_model(m, make);
  } else {
    const ContactConfig c = ContactConfig::read(scene);
    scene.reject_unknown_keys();
    name = c.normal + (c.tangential == "coulomb" ? "+coulomb" : "") + (c.rolling ? "+rolling" : "");
    with_contact_model(c, make);
  }
  return out;
}

}  // namespace

Simulation::Simulation() { ++g_alive; }
Simulation::~Simulation() { --g_alive; }
int Simulation::alive() { return g_alive.load(); }

Packing random_packing(int count, double diameter_min, double diameter_max, double density,
                       double phi, std::uint64_t seed, double speed) {
  require(count >= 2, "count must be at least 2");
  require(diameter_min > 0 && diameter_max >= diameter_min,
          "diameters must satisfy 0 < diameter_min <= diameter_max");
  require(diameter_max <= 100 * diameter_min, "diameter_max / diameter_min must not exceed 100");
  require(density > 0 && std::isfinite(density), "density must be positive");
  require(phi >= 1e-3 && phi <= kMaxGasFraction,
          "phi must lie in [0.001, " + std::to_string(kMaxGasFraction) +
              "] (random insertion jams beyond; compress from there)");
  require(speed >= 0 && std::isfinite(speed), "speed must not be negative");
  GasSpec gas;
  gas.count = count;
  gas.diameter_min = diameter_min, gas.diameter_max = diameter_max;
  gas.density = density, gas.phi = phi, gas.seed = seed, gas.speed = speed;
  Packing out;
  out.particles = random_gas(gas, out.box);
  return out;
}

Packing read_lammps_packing(const std::string& path) {
  const LammpsData d = read_lammps_data(path);
  if (d.triclinic())
    throw InputError(path + ": a triclinic box; the engine's periodic box is cuboid");
  Packing out;
  out.particles = d.particles;
  for (int k = 0; k < 3; ++k) out.box.lo[k] = d.lo[k], out.box.len[k] = d.len[k];
  return out;
}

Packing read_state_packing(const std::string& path, const std::string& group) {
  const H5Reader in(path);
  if (!in.has(group)) throw InputError(path + ": no state group " + group);
  Packing out;
  double density = 0;
  out.particles = read_state(in, group, out.box, density);
  return out;
}

std::unique_ptr<Simulation> make_simulation(const Packing& packing, const std::string& contact,
                                            const std::string& source, const DemParams& params) {
  return build(contact, source, params, packing.particles, {}, packing.box, nullptr);
}

std::unique_ptr<Simulation> restore_simulation(const ConfigState& state, const std::string& contact,
                                               const std::string& source, const DemParams& params) {
  return build(contact, source, params, state.particles, state.w, state.box, &state);
}

}  // namespace granular::api
