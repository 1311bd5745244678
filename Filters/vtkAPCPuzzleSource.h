// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAPCPuzzleSource
 * @brief   Parallel source of the "gear teeth" worst case for sort-last compositing:
 *          interleaved slabs of hexahedra whose pieces all overlap in depth.
 *
 * The domain is the box [-1,1]^3. It is cut along one axis into
 * `NumberOfPuzzlePieces * SlabsPerPiece` slabs of equal thickness; slab j belongs to puzzle
 * piece j mod NumberOfPuzzlePieces (round robin), so every piece's bounding box overlaps every
 * other's and no depth order of the pieces exists. Each slab is `Resolution x Resolution x 2`
 * hexahedra (VTK_HEXAHEDRON) with its own points, so point scalars may jump between slabs.
 * This is the weak-scaling stress test of the APC paper (Fig. "gear teeth", each rank owning
 * four layers of hexahedra interleaved with the other ranks' layers).
 *
 * Pieces: the source honours the pipeline's piece request (UPDATE_PIECE_NUMBER /
 * UPDATE_NUMBER_OF_PIECES), so under pvbatch or pvserver with N ranks each rank generates only
 * its own cells. By default there is one puzzle piece per requested piece; with
 * NumberOfPuzzlePieces = P > 0, requested piece p of n generates puzzle pieces
 * [p*P/n, (p+1)*P/n) (P < n leaves some ranks empty, which is a useful test).
 *
 * Output arrays: one point scalar array named after the chosen Field (set as active scalars),
 * and the cell array "PuzzlePiece" (the owning puzzle piece, int).
 *
 * Fields:
 * - Spheres: the paper's concentric spheres: 1 inside radius 0.35 ("red" core), 0.5 in the
 *   shell 0.6 < r < 0.8 ("blue" shell), 0 elsewhere, with smoothstep transitions 0.05 wide so
 *   that trilinear interpolation of point values is faithful.
 * - Smooth: a smooth trigonometric field with values in [0,1].
 * - Sandwich: the paper's sandwich case: a constant per slab, the owning puzzle piece divided
 *   by max(P-1, 1), so a transfer function colours each piece's slabs apart.
 *
 * @par Reference:
 * X. Huang, W. Usher, et al., "Approximate Puzzlepiece Compositing", arXiv 2501.12581.
 */

#ifndef vtkAPCPuzzleSource_h
#define vtkAPCPuzzleSource_h

#include "APCFiltersModule.h" // for export macro
#include "vtkUnstructuredGridAlgorithm.h"

class APCFILTERS_EXPORT vtkAPCPuzzleSource : public vtkUnstructuredGridAlgorithm
{
public:
  static vtkAPCPuzzleSource* New();
  vtkTypeMacro(vtkAPCPuzzleSource, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum FieldType
  {
    SPHERES = 0,
    SMOOTH = 1,
    SANDWICH = 2
  };

  ///@{
  /**
   * Number of puzzle pieces. 0 (the default) means one per requested pipeline piece.
   */
  vtkSetClampMacro(NumberOfPuzzlePieces, int, 0, 1 << 16);
  vtkGetMacro(NumberOfPuzzlePieces, int);
  ///@}

  ///@{
  /**
   * Slabs each puzzle piece owns (the paper uses 4). Default 4.
   */
  vtkSetClampMacro(SlabsPerPiece, int, 1, 4096);
  vtkGetMacro(SlabsPerPiece, int);
  ///@}

  ///@{
  /**
   * Cells per side of each slab across the slab axis (R in R x R x 2). Default 32.
   */
  vtkSetClampMacro(Resolution, int, 1, 1 << 14);
  vtkGetMacro(Resolution, int);
  ///@}

  ///@{
  /**
   * Axis the slabs are stacked along: 0 = x, 1 = y, 2 = z (default).
   */
  vtkSetClampMacro(Axis, int, 0, 2);
  vtkGetMacro(Axis, int);
  ///@}

  ///@{
  /**
   * The point scalar field; see the class description. Default SPHERES.
   */
  vtkSetClampMacro(Field, int, SPHERES, SANDWICH);
  vtkGetMacro(Field, int);
  ///@}

  /**
   * Name of the point scalar array the current Field produces.
   */
  const char* GetFieldName() const;

  /**
   * Cells of one puzzle piece: SlabsPerPiece * Resolution^2 * 2.
   */
  vtkIdType GetNumberOfCellsPerPuzzlePiece() const;

protected:
  vtkAPCPuzzleSource();
  ~vtkAPCPuzzleSource() override = default;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int NumberOfPuzzlePieces = 0;
  int SlabsPerPiece = 4;
  int Resolution = 32;
  int Axis = 2;
  int Field = SPHERES;

private:
  vtkAPCPuzzleSource(const vtkAPCPuzzleSource&) = delete;
  void operator=(const vtkAPCPuzzleSource&) = delete;
};

#endif
