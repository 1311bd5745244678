// SPDX-License-Identifier: BSD-3-Clause
// What converting one input for the ray marcher found that a user should hear about, said
// once per data change: cells skipped or made transparent, and by what rule. The counts
// are plain numbers so that they add up across processes: vtkAPCCompositePass sums them
// onto the display process, which says it once for all (Share); the mapper alone says its
// own (Emit).
#ifndef apcInputReport_h
#define apcInputReport_h

#include "APCRenderingModule.h" // for export macro

#include "vtkCellType.h"

#include <array>
#include <string>

class vtkObject;

namespace apc
{
struct ProcessGroup;

struct APCRENDERING_EXPORT InputReport
{
  enum Count
  {
    FlatCells,        // no volume (collapsed or all corners in one plane): skipped
    NonFiniteCorners, // a NaN or infinite corner coordinate: skipped
    NonFiniteScalars, // a NaN or +-inf scalar: transparent
    RGBColoursMode,   // inputs whose vector mode RGBCOLORS was rendered as the magnitude
    ComponentClamped, // inputs whose vector component did not exist and was clamped
    CountKinds
  };
  // The counts above, then the unsupported cells of each VTK cell type.
  std::array<double, CountKinds + VTK_NUMBER_OF_CELL_TYPES> Counts{};

  double& operator[](Count kind) { return this->Counts[kind]; }
  double operator[](Count kind) const { return this->Counts[kind]; }
  void AddUnsupported(int cellType) { this->Counts[CountKinds + cellType] += 1; }

  bool Empty() const;
  void Add(const InputReport& other);

  /// The cells that cannot be rendered, named by type (an error); empty if none.
  std::string Errors() const;
  /// Everything else (a warning); empty if nothing.
  std::string Warnings() const;
  /// Says Errors() and Warnings(), if any, as errors and warnings of reporter; processes
  /// (> 1) says that the counts are the sum over that many processes.
  void Emit(vtkObject* reporter, int processes = 1) const;
};

/**
 * Sums the processes' reports onto the display process, which emits the sum on reporter (a
 * collective: every process of group calls it, with an empty report if it has nothing).
 */
APCRENDERING_EXPORT void ShareInputReports(
  const ProcessGroup& group, const InputReport& local, vtkObject* reporter);
}

#endif
