// The LAMMPS data reader (atom style sphere) on small hand-written files: ids sorted,
// types to species, diameters to radii, densities to masses, box and velocities in the
// engine's units (mm, us, ug) from SI; and every malformed file rejected with an
// InputError that names the file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/dem/particles.hpp"
#include "core/lammps/lammps_data.hpp"
#include "core/run/error.hpp"
#include "kernels/contact/contact_state.hpp"

using namespace granular;

static_assert(kLammpsMaxTypes == kMaxSpecies,
              "the reader must accept exactly the species the "
              "pair tables hold");

namespace {

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "granular_" + name + ".data";
  std::ofstream(path) << text;
  return path;
}

const char* kHeader =
    "LAMMPS data file: three spheres\n"
    "\n"
    "3 atoms\n"
    "2 atom types\n"
    "\n"
    "-0.001 0.002 xlo xhi\n"
    "0 0.003 ylo yhi\n"
    "0.0005 0.0045 zlo zhi   # comment after the bounds\n"
    "\n";

// Ids out of order, one line with image flags, a comment, and velocities for two atoms.
const std::string kGood = std::string(kHeader) +
                          "Atoms # sphere\n"
                          "\n"
                          "3 1 0.0002 2500 0.0005 0.001 0.002\n"
                          "1 2 0.0004 1000 0.001 0.0015 0.0025 0 0 0\n"
                          "2 1 0.0003 2500 0.0001 0.0002 0.0003  # last atom\n"
                          "\n"
                          "Velocities\n"
                          "\n"
                          "1 0.1 0.2 -0.3 0 0 0\n"
                          "3 -0.1 0 0.05 0 0 0\n";

// Relative tolerance of a product of a few decimal constants: a few ulps.
constexpr double kTol = 1e-14;

void expect_rel(double got, double want, const char* what) {
  EXPECT_NEAR(got, want, kTol * std::fabs(want)) << what;
}

// Reads `text` written to a file and expects an InputError whose message names the file
// and contains `fragment`.
void expect_rejected(const std::string& name, const std::string& text,
                     const std::string& fragment) {
  const std::string path = write_file(name, text);
  try {
    read_lammps_data(path);
    ADD_FAILURE() << name << ": accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << name << ": " << msg;
    EXPECT_NE(msg.find(fragment), std::string::npos) << name << ": " << msg;
  }
  std::remove(path.c_str());
}

}  // namespace

TEST(LammpsData, SphereFileGivesSortedParticlesInEngineUnits) {
  const std::string path = write_file("good", kGood);
  const LammpsData d = read_lammps_data(path);
  std::remove(path.c_str());
  const HostParticles& h = d.particles;
  ASSERT_EQ(h.size(), 3);
  EXPECT_EQ(d.atom_types, 2);
  // Box: metres to millimetres.
  const double lo[3] = {-1.0, 0.0, 0.5}, len[3] = {3.0, 3.0, 4.0};
  for (int k = 0; k < 3; ++k)
    expect_rel(d.lo[k] + 1.0, lo[k] + 1.0, "lo"), expect_rel(d.len[k], len[k], "len");
  // Particles in id order 1, 2, 3: species = type - 1, radius = diameter / 2 in mm.
  const int species[3] = {1, 0, 0};
  const double radius[3] = {0.2, 0.15, 0.1}, density[3] = {1000, 2500, 2500};
  const double x[3][3] = {{1.0, 1.5, 2.5}, {0.1, 0.2, 0.3}, {0.5, 1.0, 2.0}};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(h.species[i], species[i]) << i;
    expect_rel(h.radius[i], radius[i], "radius");
    // kg/m^3 equals ug/mm^3: the density is unchanged.
    expect_rel(h.density[i], density[i], "density");
    expect_rel(h.x[i], x[i][0], "x"), expect_rel(h.y[i], x[i][1], "y"),
        expect_rel(h.z[i], x[i][2], "z");
  }
  // Velocities: m/s = 1e3 mm / 1e6 us = 1e-3 mm/us; atom 2 has none.
  expect_rel(h.vx[0], 1e-4, "vx"), expect_rel(h.vy[0], 2e-4, "vy"),
      expect_rel(h.vz[0], -3e-4, "vz");
  for (double vk : {h.vx[1], h.vy[1], h.vz[1]}) EXPECT_EQ(vk, 0.0);
  expect_rel(h.vx[2], -1e-4, "vx"), expect_rel(h.vz[2], 5e-5, "vz");
  // Masses: SI mass rho (pi/6) d^3 in kg is 1e9 times the engine's mass in ug.
  auto p = Particles<Kokkos::DefaultHostExecutionSpace>::from_host(h);
  const double d_si[3] = {0.0004, 0.0003, 0.0002};
  for (int i = 0; i < 3; ++i)
    expect_rel(p.mass(i), density[i] * M_PI / 6 * d_si[i] * d_si[i] * d_si[i] * 1e9, "mass");
}

TEST(LammpsData, UnitScalesOfOneReadTheFileUnchanged) {
  const std::string path = write_file("identity", kGood);
  const LammpsData d = read_lammps_data(path, 1.0, 1.0, 1.0);
  std::remove(path.c_str());
  const HostParticles& h = d.particles;
  ASSERT_EQ(h.size(), 3);
  EXPECT_EQ(h.density[0], 1000.0);  // no hidden kg -> ug factor when no conversion is asked
  EXPECT_EQ(h.radius[0], 0.0002);
  EXPECT_EQ(h.vy[0], 0.2);
  EXPECT_EQ(d.len[2], 0.0045 - 0.0005);
  // Mixed scales: grams and centimetres (cgs): density factor 1e3 / 1e2^3 = 1e-3 (g/cm^3).
  const std::string path2 = write_file("cgs", kGood);
  const LammpsData c = read_lammps_data(path2, 1e2, 1.0, 1e3);
  std::remove(path2.c_str());
  expect_rel(c.particles.density[0], 1.0, "density in g/cm^3");
}

TEST(LammpsData, MalformedFilesAreInputErrorsNamingTheFile) {
  const std::string atoms_ok = "Atoms\n\n1 1 0.0002 2500 0 0 0\n2 2 0.0002 2500 0.001 0 0\n";
  auto file = [](const std::string& types, const std::string& body) {
    return "title\n\n2 atoms\n" + types +
           " atom types\n\n0 1 xlo xhi\n0 1 ylo yhi\n0 1 zlo zhi\n\n" + body;
  };
  // Type 0 would be species -1.
  expect_rejected("type_zero",
                  file("2", "Atoms\n\n1 0 0.0002 2500 0 0 0\n2 1 0.0002 2500 0.001 0 0\n"),
                  "atom type 0");
  // Type beyond the header's count of atom types.
  expect_rejected("type_over_header",
                  file("2", "Atoms\n\n1 1 0.0002 2500 0 0 0\n2 3 0.0002 2500 0.001 0 0\n"),
                  "atom type 3");
  // Type within the header but beyond the species the pair tables hold.
  expect_rejected("type_over_table",
                  file("6", "Atoms\n\n1 1 0.0002 2500 0 0 0\n2 5 0.0002 2500 0.001 0 0\n"),
                  "atom type 5");
  // Non-integer type.
  expect_rejected("type_fraction",
                  file("2", "Atoms\n\n1 1.5 0.0002 2500 0 0 0\n2 1 0.0002 2500 0.001 0 0\n"),
                  "atom type 1.5");
  // Truncated Atoms line (file cut short), with the line number in the message.
  expect_rejected("truncated", file("2", "Atoms\n\n1 1 0.0002 2500 0 0 0\n2 1 0.0002 2500"),
                  ":13:");
  // Garbage in a number.
  expect_rejected("garbage",
                  file("2", "Atoms\n\n1 1 0.0002 2500 0 0 0\n2 1 0.0002 25x0 0.001 0 0\n"),
                  "not a number");
  // Fewer atoms than announced, and a duplicated id.
  expect_rejected("missing_atom", file("2", "Atoms\n\n1 1 0.0002 2500 0 0 0\n"), "announces 2");
  expect_rejected("duplicate",
                  file("2", "Atoms\n\n1 1 0.0002 2500 0 0 0\n1 1 0.0002 2500 0.001 0 0\n"),
                  "twice");
  // Non-positive diameter or density.
  expect_rejected("zero_diameter",
                  file("2", "Atoms\n\n1 1 0 2500 0 0 0\n2 1 0.0002 2500 0.001 0 0\n"), "positive");
  expect_rejected("negative_density",
                  file("2", "Atoms\n\n1 1 0.0002 -1 0 0 0\n2 1 0.0002 2500 0.001 0 0\n"),
                  "positive");
  // A velocity for an atom that does not exist.
  expect_rejected("stray_velocity", file("2", atoms_ok + "\nVelocities\n\n7 0 0 0 0 0 0\n"),
                  "atom 7");
  // An atom a thousand box lengths away (at 1e308 it used to reach the bin index as NaN cast
  // to an integer: a segfault; at 1e20 the refusal blamed two periodic images).
  expect_rejected("huge_x",
                  file("2", "Atoms\n\n1 1 0.0002 2500 1e308 0 0\n2 1 0.0002 2500 0.001 0 0\n"),
                  "more than 1000 box lengths outside the box along x");
  expect_rejected("far_z",
                  file("2", "Atoms\n\n1 1 0.0002 2500 0 0 1e20\n2 1 0.0002 2500 0.001 0 0\n"),
                  ":12: atom 1 lies more than 1000 box lengths outside the box along z");
  // No atom count in the header.
  expect_rejected("no_count", "title\n\n1 atom types\n\nAtoms\n\n1 1 0.0002 2500 0 0 0\n", "atoms");
  // A missing file.
  const std::string missing = ::testing::TempDir() + "granular_no_such_file.data";
  try {
    read_lammps_data(missing);
    ADD_FAILURE() << "missing file accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
}

TEST(LammpsData, TiltLineIdsAndSpinsAreKept) {
  std::string text = kGood;
  text.insert(text.find("Atoms"), "0.0004 -0.0002 0.0001 xy xz yz\n\n");
  text.replace(text.find("1 0.1 0.2 -0.3 0 0 0"), 20, "1 0.1 0.2 -0.3 5 -6 7");
  const std::string path = write_file("triclinic", text);
  const LammpsData d = read_lammps_data(path, 1.0, 1e6, 1.0);  // spins in 1/us
  std::remove(path.c_str());
  ASSERT_TRUE(d.triclinic());
  EXPECT_EQ(d.tilt[0], 0.0004);
  EXPECT_EQ(d.tilt[1], -0.0002);
  EXPECT_EQ(d.tilt[2], 0.0001);
  EXPECT_EQ(d.ids, (std::vector<long>{1, 2, 3}));
  expect_rel(d.particles.wx[0], 5e-6, "spin x");
  expect_rel(d.particles.wy[0], -6e-6, "spin y");
  expect_rel(d.particles.wz[0], 7e-6, "spin z");
  EXPECT_EQ(d.particles.wx[1], 0.0);  // atom 2 has no Velocities line
}
