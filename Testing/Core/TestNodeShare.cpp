// The default thread count's rule (apcParallel.h), alone: what an MPI test on this 2-core
// machine cannot reach (64-core nodes with sockets, one process per node, more processes than
// cores, masks shared by some processes and not others).
#include "apcParallel.h"

#include <gtest/gtest.h>

#include <vector>

namespace
{
// The mask of cores [first, first + count).
apc::CoreMask Cores(int first, int count)
{
  apc::CoreMask mask(16, 0);
  for (int core = first; core < first + count; ++core)
  {
    mask[core / 64] |= uint64_t(1) << (core % 64);
  }
  return mask;
}

// processes processes, each with the mask mask(p); process self's default.
template <class MaskOf>
int Share(int processes, MaskOf mask, int self)
{
  std::vector<apc::CoreMask> masks;
  for (int p = 0; p < processes; ++p)
  {
    masks.push_back(mask(p));
  }
  return apc::NodeShareOfThreads(masks, static_cast<size_t>(self));
}
}

TEST(NodeShare, UnboundProcessesTakeTwiceTheirShareAtMostTheNode)
{
  auto node = [](int cores) { return [cores](int) { return Cores(0, cores); }; };
  EXPECT_EQ(Share(1, node(64), 0), 64); // alone: every core, not 128
  EXPECT_EQ(Share(64, node(64), 5), 2); // 128 threads on the node, not 4,096
  EXPECT_EQ(Share(16, node(64), 0), 8); // share 4
  EXPECT_EQ(Share(4, node(2), 3), 2);   // share below a core: one, twice
  EXPECT_EQ(Share(2, node(2), 0), 2);
  EXPECT_EQ(Share(4, node(6), 0), 2); // share 1.5, rounded down
  EXPECT_EQ(Share(3, node(8), 2), 4); // share 2.67
  EXPECT_EQ(Share(3, node(3), 0), 2); // 3 x 1/3 of a core each is one core, not none
}

TEST(NodeShare, ProcessesBoundToTheirOwnCoresKeepTheirMask)
{
  // mpirun's default up to 2 ranks, --bind-to core: one core each.
  EXPECT_EQ(Share(
              2, [](int p) { return Cores(p, 1); }, 1),
    1);
  EXPECT_EQ(Share(
              64, [](int p) { return Cores(p, 1); }, 63),
    1);
  // Eight processes bound to eight cores each: their masks, as TBB would take.
  EXPECT_EQ(Share(
              8, [](int p) { return Cores(8 * p, 8); }, 3),
    8);
  // Two processes bound to the same core (overloaded): still one thread, not none.
  EXPECT_EQ(Share(
              4, [](int p) { return Cores(p % 2, 1); }, 2),
    1);
}

TEST(NodeShare, ProcessesBoundToASocketShareIt)
{
  // 64 ranks on two 32-core sockets (mpirun's default above 2 ranks binds to the socket):
  // the mask has 32 cores, but 32 processes share them.
  auto sockets = [](int p) { return Cores(p < 32 ? 0 : 32, 32); };
  EXPECT_EQ(Share(64, sockets, 0), 2);
  EXPECT_EQ(Share(64, sockets, 40), 2);
  // 4 ranks on the same two sockets: 16 cores' share each, twice is the socket.
  EXPECT_EQ(Share(
              4, [](int p) { return Cores(p < 2 ? 0 : 32, 32); }, 3),
    32);
  // Uneven: 3 ranks on socket 0, 1 on socket 1.
  auto uneven = [](int p) { return Cores(p < 3 ? 0 : 32, 32); };
  EXPECT_EQ(Share(4, uneven, 0), 20); // 10.67 cores' share
  EXPECT_EQ(Share(4, uneven, 3), 32); // its socket alone
}

TEST(NodeShare, MixedMasksCountWhoMayRunOnEachCore)
{
  // Process 0 unbound on 4 cores, processes 1-3 bound to cores 1-3: process 0 shares cores
  // 1-3 with one process each and has core 0 alone (1 + 3 / 2 = 2.5 cores).
  auto mixed = [](int p) { return p == 0 ? Cores(0, 4) : Cores(p, 1); };
  EXPECT_EQ(Share(4, mixed, 0), 4);
  EXPECT_EQ(Share(4, mixed, 2), 1);
  // Cores above 64 (a second mask word).
  EXPECT_EQ(Share(
              2, [](int p) { return Cores(64 + 4 * p, 4); }, 1),
    4);
  EXPECT_EQ(Share(
              4, [](int) { return Cores(60, 8); }, 0),
    4); // across the words' edge
}

TEST(NodeShare, NoMaskLeavesItToTBB)
{
  EXPECT_EQ(apc::NodeShareOfThreads({}, 0), 0);
  EXPECT_EQ(apc::NodeShareOfThreads({ Cores(0, 2) }, 1), 0);          // self out of range
  EXPECT_EQ(apc::NodeShareOfThreads({ apc::CoreMask(16, 0) }, 0), 0); // an empty mask
}
