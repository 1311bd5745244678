// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAPCGraphPartition
 * @brief   Cuts unstructured grids into K jagged pieces with a graph partitioner (METIS) on
 *          the cell dual graph, and moves each piece to its rank.
 *
 * The pieces a CFD code writes are cut by graph partitioners (ParMETIS, Scotch): they are
 * balanced, have short cuts, and are jagged and interleaved, so their bounding boxes overlap
 * in depth. That is the case APC is made for, and the one ParaView's own redistribution
 * (kd-tree, convex blocks) never produces. This filter makes such pieces from any mesh.
 *
 * Algorithm: the cells are the vertices of the dual graph, and two cells are neighbours when
 * they share a facet (a face of a 3D cell, an edge of a 2D cell), found by the set of the
 * facet's point positions; polyhedra take part through their face streams, quadratic and
 * other cells through vtkCell faces. Each rank matches the facets of its own cells and sends
 * rank 0 only its graph edges and the facets it could not match (its boundary, with
 * coordinates); rank 0 matches those across ranks, runs METIS_PartGraphKway (K >= 2; K = 1 is
 * trivial) and scatters the part of every cell back. So rank 0 holds the whole graph
 * (O(cells) memory and METIS time) but never the cells or their arrays. Then, unless
 * LabelOnly is on, every rank sends each of its cells to the rank of its piece
 * (vtkDIYDataExchanger, one all-to-all) and appends what it receives.
 *
 * With the PT-Scotch partitioner (the default on more than one rank, see SetPartitioner) no
 * rank gathers the graph: each unmatched facet goes to the rank its point positions hash to,
 * where it meets its other half, and the edge goes back to both cells' ranks, all point to
 * point; PT-Scotch (SCOTCH_dgraphPart) then partitions the distributed graph, each rank
 * holding only its own cells and their neighbours' ids. The stages are private
 * helpers: apcPartitionInput (the input walked into meshes), apcPartitionGraph (the dual graph
 * and its partition), apcPartitionMove (label or move); the VTK-free parts are in Filters/Core.
 *
 * Pieces to ranks: contiguous blocks, rank r of R gets pieces [r*K/R, (r+1)*K/R), so with
 * K > R a rank owns several pieces (the `PartitionId` cell array tells them apart) and with
 * K < R some ranks get no cells.
 *
 * Output: the input's type. For a vtkUnstructuredGrid, the cells of this rank's pieces with
 * all their point and cell arrays plus the int cell array `PartitionId`. Composite inputs
 * (vtkMultiBlockDataSet, vtkPartitionedDataSet, vtkPartitionedDataSetCollection) are
 * partitioned block by block: every unstructured-grid leaf of a multiblock separately, and
 * each vtkPartitionedDataSet as one mesh (its partitions on all ranks together), whose output
 * has one partition per piece this rank owns. The composite structure must be the same on
 * all ranks (as ParaView's readers give it).
 *
 * No ghost cells: duplicate (ghost) cells of the input are left out, the output has no ghost
 * array and no ghost layers. Points are not merged: a point shared by cells that arrive from
 * different ranks appears once per source rank (use Clean to Grid for a conforming mesh).
 * Points are identified by their exact coordinates (pieces cut from one mesh share them
 * bit for bit), so two cells touching only through coincident but distinct points still count
 * as neighbours.
 *
 * LabelOnly: computes the same partition but moves nothing; each rank's output is its input
 * with `PartitionId` added (-1 on ghost cells).
 *
 * Errors (vtkErrorMacro on every rank, output empty, no rank left waiting): input not an
 * unstructured grid or a composite of them, NumberOfPartitions < 0, no cells on any rank, a
 * composite structure that differs across ranks, the partitioner failing. Every rank agrees on the
 * failure (an all-reduce of a status) before the next collective.
 *
 * @par References:
 * G. Karypis, V. Kumar, "A fast and high quality multilevel scheme for partitioning irregular
 * graphs", SIAM J. Sci. Comput. 20(1), 1998 (METIS).
 * C. Chevalier, F. Pellegrini, "PT-Scotch: A tool for efficient parallel graph ordering",
 * Parallel Computing 34(6-8), 2008 (PT-Scotch).
 */

#ifndef vtkAPCGraphPartition_h
#define vtkAPCGraphPartition_h

#include "APCFiltersModule.h" // for export macro
#include "vtkPassInputTypeAlgorithm.h"

class vtkMultiProcessController;

class APCFILTERS_EXPORT vtkAPCGraphPartition : public vtkPassInputTypeAlgorithm
{
public:
  static vtkAPCGraphPartition* New();
  vtkTypeMacro(vtkAPCGraphPartition, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /**
   * Number of pieces K. 0 (the default) means one per rank of the controller. Negative
   * values are an error.
   */
  vtkSetMacro(NumberOfPartitions, int);
  vtkGetMacro(NumberOfPartitions, int);
  ///@}

  enum PartitionerType
  {
    AUTO = 0,    ///< METIS on one process, PT-Scotch on more
    METIS = 1,   ///< the whole graph on rank 0, METIS_PartGraphKway
    PTSCOTCH = 2 ///< the graph distributed, each rank its own cells, SCOTCH_dgraphPart
  };

  ///@{
  /**
   * Which graph partitioner cuts the pieces. METIS needs the whole dual graph on rank 0, and
   * the boundary facets it is matched from, so rank 0's memory grows with the whole mesh while
   * the other ranks' shrink with their share, and METIS runs serially; PT-Scotch keeps each
   * rank's part of the graph where it is and partitions in parallel, so no rank holds more
   * than its own share. Both balance the pieces to about 3 %. Default AUTO (METIS on one
   * process, PT-Scotch on more). docs/evaluation.md, section 6, measures both.
   */
  vtkSetClampMacro(Partitioner, int, AUTO, PTSCOTCH);
  vtkGetMacro(Partitioner, int);
  ///@}

  ///@{
  /**
   * Seed of the partitioner's random number generator (METIS_OPTION_SEED, SCOTCH_randomSeed).
   * The same graph, K, seed and number of processes give the same partition. Default 0.
   */
  vtkSetMacro(Seed, int);
  vtkGetMacro(Seed, int);
  ///@}

  ///@{
  /**
   * Keep every cell on its rank and only add `PartitionId`. Default off (move the pieces).
   */
  vtkSetMacro(LabelOnly, bool);
  vtkGetMacro(LabelOnly, bool);
  vtkBooleanMacro(LabelOnly, bool);
  ///@}

  ///@{
  /**
   * The processes to partition across. Defaults to the global controller; none means one
   * process.
   */
  void SetController(vtkMultiProcessController*);
  vtkGetObjectMacro(Controller, vtkMultiProcessController);
  ///@}

  /**
   * Name of the cell array holding each cell's piece: "PartitionId".
   */
  static const char* GetPartitionIdArrayName() { return "PartitionId"; }

  ///@{
  /**
   * What the last execution measured, summed over the meshes it partitioned (the same on
   * every rank): cut edges of the dual graph, the largest piece over the mean piece
   * (METIS aims at <= 1.03), and wall seconds of building the graph (facets on every rank
   * plus the matching on rank 0), of METIS, and of moving the cells.
   */
  vtkGetMacro(LastEdgeCut, vtkIdType);
  vtkGetMacro(LastImbalance, double);
  vtkGetMacro(LastGraphSeconds, double);
  vtkGetMacro(LastPartitionSeconds, double);
  vtkGetMacro(LastExchangeSeconds, double);
  ///@}

protected:
  vtkAPCGraphPartition();
  ~vtkAPCGraphPartition() override;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int NumberOfPartitions = 0;
  int Partitioner = AUTO;
  int Seed = 0;
  bool LabelOnly = false;
  vtkMultiProcessController* Controller = nullptr;

  vtkIdType LastEdgeCut = 0;
  double LastImbalance = 0;
  double LastGraphSeconds = 0;
  double LastPartitionSeconds = 0;
  double LastExchangeSeconds = 0;

private:
  vtkAPCGraphPartition(const vtkAPCGraphPartition&) = delete;
  void operator=(const vtkAPCGraphPartition&) = delete;
};

#endif
