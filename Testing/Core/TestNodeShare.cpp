// The default thread count's rule (apcParallel.h), alone: what an MPI test on this 2-core
// machine cannot reach (64-core nodes, one process per node, more processes than cores).
#include "apcParallel.h"

#include <gtest/gtest.h>

TEST(NodeShare, BoundProcessesKeepTheirMask)
{
  EXPECT_EQ(apc::NodeShareOfThreads(64, 8, 8), 0);
  EXPECT_EQ(apc::NodeShareOfThreads(2, 1, 2), 0);
}

TEST(NodeShare, UnboundProcessesTakeTwiceTheirShareAtMostTheNode)
{
  EXPECT_EQ(apc::NodeShareOfThreads(64, 64, 1), 64); // alone: every core, not 128
  EXPECT_EQ(apc::NodeShareOfThreads(64, 64, 64), 2); // 128 threads on the node, not 4,096
  EXPECT_EQ(apc::NodeShareOfThreads(64, 64, 16), 8); // share 4
  EXPECT_EQ(apc::NodeShareOfThreads(64, 0, 16), 8);  // mask unknown: unbound
  EXPECT_EQ(apc::NodeShareOfThreads(2, 2, 4), 2);    // share below a core: one, twice
  EXPECT_EQ(apc::NodeShareOfThreads(2, 2, 2), 2);
  EXPECT_EQ(apc::NodeShareOfThreads(6, 6, 4), 2); // share 1 (6 / 4 rounded down)
  EXPECT_EQ(apc::NodeShareOfThreads(8, 8, 3), 4);
}

TEST(NodeShare, UnknownNodeLeavesItToTBB)
{
  EXPECT_EQ(apc::NodeShareOfThreads(0, 4, 1), 0);
  EXPECT_EQ(apc::NodeShareOfThreads(4, 4, 0), 0);
}
