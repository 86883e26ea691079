// The on-chip chain kernel (kernels/chain/chain_on_chip.hpp) against the global sweep it
// replaces on devices: the same bits for both laws and both boundaries, with one thread per
// chain and with several threads exchanging their end displacements; contact opening still
// stops the run; a chain it cannot hold is refused, not silently run another way.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "kernels/chain/chain_verlet.hpp"
#include "tests/exec_spaces.hpp"

using namespace granular;

namespace {

template <class Space>
class ChainOnChipTest : public ::testing::Test {};
TYPED_TEST_SUITE(ChainOnChipTest, granular::testing::ExecSpaces);

ChainSpec spec_of(int n, ChainBoundary bc, ChainForce law, double xi) {
  ChainSpec s;
  s.beads = n, s.boundary = bc, s.force = law, s.xi = xi, s.seed = 19;
  return s;
}

template <class Space>
std::vector<double> all_of(
    const Kokkos::View<double**, Kokkos::LayoutRight, typename Space::memory_space>& f) {
  auto h = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), f);
  return std::vector<double>(h.data(), h.data() + h.size());
}

// Sets an impulse on bead 0 and a displacement pattern, so that every contact (the walls'
// and the ring's closing one included) carries a different force from the first step on.
template <class Space>
void start(ChainBatch<Space>& c) {
  chain_set_impulse(c, 0, 0.02);
  auto u = c.u;
  const int N = c.N;
  Kokkos::parallel_for(
      Kokkos::RangePolicy<Space>(0, c.R * N), KOKKOS_LAMBDA(const int k) {
        const int r = k / N, i = k % N;
        u(r, i) = 1e-3 * ((i * 7 + r * 3) % 11 - 5);
      });
  chain_accelerations(c);
}

// A team body that does nothing: asks a team policy how large a team may be. A functor, not
// a lambda: nvcc refuses device lambdas inside a test body (a private member function).
struct EmptyTeamBody {
  template <class Member>
  KOKKOS_INLINE_FUNCTION void operator()(const Member&) const {}
};

template <class Space>
void expect_same_state(const ChainBatch<Space>& x, const ChainBatch<Space>& y,
                       const std::string& what) {
  EXPECT_EQ(all_of<Space>(x.u), all_of<Space>(y.u)) << what;
  EXPECT_EQ(all_of<Space>(x.v), all_of<Space>(y.v)) << what;
  EXPECT_EQ(all_of<Space>(x.a), all_of<Space>(y.a)) << what;
}

}  // namespace

TYPED_TEST(ChainOnChipTest, OnChipKernelGivesTheGlobalSweepsBitsForBothLawsAndBoundaries) {
  for (auto law : {ChainForce::Hertz, ChainForce::Linear})
    for (auto bc : {ChainBoundary::Fixed, ChainBoundary::Periodic})
      for (int n : {2, 5, 37, 300}) {
        const std::string what = std::string(law == ChainForce::Hertz ? "hertz" : "linear") +
                                 (bc == ChainBoundary::Fixed ? " fixed " : " ring ") +
                                 std::to_string(n) + " beads";
        ChainBatch<TypeParam> global(spec_of(n, bc, law, 0.3), ChainBatch<TypeParam>::first(3));
        ChainBatch<TypeParam> chip(spec_of(n, bc, law, 0.3), ChainBatch<TypeParam>::first(3));
        global.kernel = ChainKernel::Global;
        chip.kernel = ChainKernel::OnChip;
        start(global), start(chip);
        for (long steps : {1L, 7L, 250L}) {  // several calls: each reloads the chain
          chain_advance(global, 0.05, steps);
          chain_advance(chip, 0.05, steps);
          expect_same_state(global, chip, what + ", after a call of " + std::to_string(steps));
        }
        EXPECT_NE(all_of<TypeParam>(chip.v), std::vector<double>(chip.v.size(), 0.0)) << what;
      }
}

// Four beads per thread, as many threads as a team of this space takes (up to 16): the
// blocks' end displacements go through the halo, and the contact between two blocks is
// computed by both threads.
TYPED_TEST(ChainOnChipTest, ThreadsOfOneChainExchangeTheirEndsAndKeepTheGlobalSweepsBits) {
  const int threads = std::min(16, chain_team_max<TypeParam>(EmptyTeamBody{}));
  for (auto law : {ChainForce::Hertz, ChainForce::Linear})
    for (auto bc : {ChainBoundary::Fixed, ChainBoundary::Periodic}) {
      const int n = 4 * threads - 1;  // the last thread owns three beads
      ChainBatch<TypeParam> global(spec_of(n, bc, law, 0.2), ChainBatch<TypeParam>::first(2));
      ChainBatch<TypeParam> chip(spec_of(n, bc, law, 0.2), ChainBatch<TypeParam>::first(2));
      global.kernel = ChainKernel::Global;
      start(global), start(chip);
      chain_advance(global, 0.05, 120);
      if (law == ChainForce::Hertz)
        ASSERT_TRUE((chain_sweep_on_chip<ChainForce::Hertz, 4>(chip, 0.05, 120)));
      else
        ASSERT_TRUE((chain_sweep_on_chip<ChainForce::Linear, 4>(chip, 0.05, 120)));
      expect_same_state(global, chip, std::to_string(threads) + " threads");
      // Where the space runs teams of several threads, the halo was exercised.
      if (TypeParam::concurrency() > 1) {
        EXPECT_GT(threads, 1);
      }
    }
}

TYPED_TEST(ChainOnChipTest, OnChipKernelStopsTheRunWhenAContactOpens) {
  ChainBatch<TypeParam> c(spec_of(16, ChainBoundary::Fixed, ChainForce::Hertz, 0.0), {0});
  c.kernel = ChainKernel::OnChip;
  chain_set_impulse(c, 0, 2.0);  // far beyond the pre-compression: the contact behind opens
  chain_accelerations(c);
  EXPECT_THROW(chain_advance(c, 0.05, 200), PhysicsError);
}

TYPED_TEST(ChainOnChipTest, AChainTooLongForTheOnChipKernelIsRefusedNamingTheAlternative) {
  constexpr bool host =
      Kokkos::SpaceAccessibility<Kokkos::HostSpace, typename TypeParam::memory_space>::accessible;
  if constexpr (host) {
    const int n = 4096 * chain_team_max<TypeParam>(EmptyTeamBody{}) + 1;
    ChainBatch<TypeParam> c(spec_of(n, ChainBoundary::Fixed, ChainForce::Linear, 0.0), {0});
    c.kernel = ChainKernel::OnChip;
    chain_set_impulse(c, 0, 0.01);
    chain_accelerations(c);
    try {
      chain_advance(c, 0.05, 3);
      FAIL() << "a chain of " << n << " beads ran on chip on a host space";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("global kernel"), std::string::npos) << e.what();
    }
  }
}

TEST(ChainKernelOption, UnknownKernelNameListsTheChoices) {
  EXPECT_EQ(parse_chain_kernel("on_chip"), ChainKernel::OnChip);
  try {
    parse_chain_kernel("shared");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("auto, global or on_chip"), std::string::npos);
  }
}
