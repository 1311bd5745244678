// SPDX-License-Identifier: BSD-3-Clause
// vtkAPCGraphPartition's last stage: every cell labelled with its piece (the int cell array
// PartitionId, -1 on ghost cells), and, unless only labelling, sent to the rank of its piece in
// one all-to-all (vtkDIYDataExchanger). Rank r of R owns the pieces [r*K/R, (r+1)*K/R).
#ifndef apcPartitionMove_h
#define apcPartitionMove_h

#include "apcPartitionInput.h"

#include <string>
#include <vector>

class vtkMultiProcessController;

namespace apc
{
namespace partition
{

// Installs a unit with no cells on any rank: empty, with its arrays, whatever the mode.
void InstallEmpty(const Unit& unit, const LocalCells& cells);

// Installs this rank's cells of the unit, each with its piece (piece: per cell of cells, in
// graph order), where they are.
void InstallLabelled(const Unit& unit, const LocalCells& cells, const int* piece);

// Sends every cell to the rank of its piece and installs what this rank receives: one grid,
// or one partition per piece this rank owns for a partitioned unit. Collective. Returns an
// error message, the same kind on every rank (all agree on a failed exchange), or "".
std::string MovePieces(const Unit& unit, const LocalCells& cells, const std::vector<int>& piece,
  int pieces, vtkMultiProcessController* controller);

} // namespace partition
} // namespace apc

#endif
