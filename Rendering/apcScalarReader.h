// SPDX-License-Identifier: BSD-3-Clause
// One value per tuple of a VTK array, as a ScalarSelection asks for it: the component, or the
// magnitude. Reads float and double arrays in VTK's usual layout straight from memory (no
// virtual call per value), other arrays through vtkDataArray; the values are the same either
// way (each component is widened to double, as GetComponent does). Safe to call from several
// threads at once on the direct path (IsDirect()).
#ifndef apcScalarReader_h
#define apcScalarReader_h

#include "apcCellMeshFromVTK.h"
#include "apcInputReport.h"

#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFloatArray.h"

#include <algorithm>
#include <cmath>

namespace apc
{

class ScalarReader
{
public:
  ScalarReader(const ScalarSelection& selection, InputReport& report)
    : Array(selection.Array)
    , Components(selection.Array->GetNumberOfComponents())
  {
    if (auto* floats = vtkFloatArray::FastDownCast(this->Array))
    {
      this->Floats = floats->GetPointer(0);
    }
    else if (auto* doubles = vtkDoubleArray::FastDownCast(this->Array))
    {
      this->Doubles = doubles->GetPointer(0);
    }
    if (this->Components == 1)
    {
      this->Component = 0;
      return;
    }
    if (selection.VectorMode == vtkScalarsToColors::COMPONENT)
    {
      this->Component = std::min(std::max(selection.VectorComponent, 0), this->Components - 1);
      if (this->Component != selection.VectorComponent)
      {
        report[InputReport::ComponentClamped] = 1;
      }
    }
    else if (selection.VectorMode == vtkScalarsToColors::RGBCOLORS)
    {
      report[InputReport::RGBColoursMode] = 1;
    }
  }

  // Whether values come straight from memory (then any thread may read them).
  bool IsDirect() const { return this->Floats || this->Doubles; }

  float operator()(vtkIdType tuple) const
  {
    if (this->Component >= 0)
    {
      return static_cast<float>(this->Get(tuple, this->Component));
    }
    double sum = 0;
    for (int c = 0; c < this->Components; ++c)
    {
      const double v = this->Get(tuple, c);
      sum += v * v;
    }
    return static_cast<float>(std::sqrt(sum));
  }

private:
  double Get(vtkIdType tuple, int component) const
  {
    const vtkIdType at = tuple * this->Components + component;
    return this->Floats ? static_cast<double>(this->Floats[at])
      : this->Doubles   ? this->Doubles[at]
                        : this->Array->GetComponent(tuple, component);
  }

  vtkDataArray* Array;
  const float* Floats = nullptr;
  const double* Doubles = nullptr;
  int Components;
  int Component = -1; // the magnitude
};

}

#endif
