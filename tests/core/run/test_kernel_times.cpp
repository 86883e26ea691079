// The kernel timer (core/run/kernel_times.hpp) files every dispatch under the phase open when
// it ran, counts every call, keeps nested phases apart, and sees nothing once stopped: the
// breakdown `granular run --kernel-times` writes adds up.
#include <gtest/gtest.h>

#include <Kokkos_Core.hpp>
#include <string>

#include "core/run/kernel_times.hpp"

using namespace granular;

namespace {
const kernel_times::Region* find_region(const std::vector<kernel_times::Region>& rs,
                                        const std::string& name) {
  for (const auto& r : rs)
    if (r.name == name) return &r;
  return nullptr;
}
const kernel_times::Kernel* find_kernel(const kernel_times::Region& r, const std::string& name) {
  for (const auto& k : r.kernels)
    if (k.name == name) return &k;
  return nullptr;
}
void touch(const char* label, int n) {
  Kokkos::View<double*, Kokkos::HostSpace> v("v", n);
  Kokkos::parallel_for(
      label, Kokkos::RangePolicy<Kokkos::DefaultHostExecutionSpace>(0, n),
      KOKKOS_LAMBDA(const int i) { v(i) = 1.0 / (1.0 + i); });
}
}  // namespace

TEST(KernelTimes, EveryCallIsFiledUnderTheInnermostOpenPhaseAndNothingAfterStop) {
  touch("before_start", 10);  // not counted: the timer is not running yet
  kernel_times::start(false);
  touch("loose", 10);
  touch("loose", 10);
  {
    KernelRegion phase("phase");
    touch("work", 200000);
    touch("work", 200000);
    double sum = 0;
    Kokkos::parallel_reduce(
        "sum", Kokkos::RangePolicy<Kokkos::DefaultHostExecutionSpace>(0, 1000),
        KOKKOS_LAMBDA(const int i, double& s) { s += i; }, sum);
    EXPECT_EQ(sum, 499500.0);
    {
      KernelRegion inner("inner");
      touch("work", 10);
    }
  }
  {
    KernelRegion again("phase");  // a second entry into the same phase adds to it
    touch("work", 10);
  }
  kernel_times::stop();
  touch("after_stop", 10);

  const auto rs = kernel_times::regions();
  const auto* loose = find_region(rs, "");
  const auto* phase = find_region(rs, "phase");
  const auto* inner = find_region(rs, "phase / inner");
  ASSERT_TRUE(loose && phase && inner);
  // Kokkos' own allocations may dispatch initialisation kernels: count only ours.
  ASSERT_TRUE(find_kernel(*loose, "loose"));
  EXPECT_EQ(find_kernel(*loose, "loose")->calls, 2);
  EXPECT_FALSE(find_kernel(*loose, "before_start"));
  EXPECT_FALSE(find_kernel(*loose, "after_stop"));
  for (const auto& r : rs) EXPECT_FALSE(find_kernel(r, "after_stop")) << r.name;
  ASSERT_TRUE(find_kernel(*phase, "work") && find_kernel(*phase, "sum"));
  EXPECT_EQ(find_kernel(*phase, "work")->calls, 3);
  EXPECT_EQ(find_kernel(*phase, "sum")->calls, 1);
  ASSERT_TRUE(find_kernel(*inner, "work"));
  EXPECT_EQ(find_kernel(*inner, "work")->calls, 1);
  EXPECT_EQ(phase->entries, 2);
  EXPECT_EQ(inner->entries, 1);
  // The kernels of a phase ran inside it, one after another: their spans fit in its wall time.
  double kernels = 0;
  for (const auto& k : phase->kernels) kernels += k.seconds;
  EXPECT_GT(find_kernel(*phase, "work")->seconds, 0.0);
  EXPECT_LE(kernels, phase->wall_seconds);
  EXPECT_LE(inner->wall_seconds, phase->wall_seconds);
  const std::string j = kernel_times::json().dump();
  EXPECT_NE(j.find("\"phase / inner\""), std::string::npos);
  EXPECT_NE(j.find("\"(outside any region)\""), std::string::npos);
}

TEST(KernelTimes, APhaseOpenedWhileTheTimerIsOffCostsNothingAndIsNotRecorded) {
  kernel_times::start(false);
  kernel_times::stop();
  {
    KernelRegion off("off");
    touch("work", 10);
  }
  EXPECT_FALSE(find_region(kernel_times::regions(), "off"));
  EXPECT_FALSE(kernel_times::running());
}
