// Every transfer function the tests and benchmarks render with, so that a test and the
// benchmark that repeats its scene cannot drift apart.
#ifndef apcTestTransferFunctions_h
#define apcTestTransferFunctions_h

#include "apcTransferTable.h"

#include "vtkColorTransferFunction.h"
#include "vtkNew.h"
#include "vtkPiecewiseFunction.h"
#include "vtkSmartPointer.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <array>
#include <vector>

namespace apctest
{

struct TransferFunction
{
  double Min = 0.0;
  double Max = 1.0;
  // (scalar, r, g, b) and (scalar, alpha) nodes.
  std::vector<std::array<double, 4>> Colours = { { 0.0, 1.0, 0.5, 0.25 }, { 1.0, 1.0, 0.5, 0.25 } };
  std::vector<std::array<double, 2>> Opacities = { { 0.0, 0.2 }, { 1.0, 0.2 } };
  double UnitDistance = 1.0;
};

// The VTK volume property of a transfer function.
inline vtkSmartPointer<vtkVolumeProperty> MakeVolumeProperty(const TransferFunction& tf)
{
  vtkNew<vtkColorTransferFunction> colour;
  for (const auto& c : tf.Colours)
  {
    colour->AddRGBPoint(c[0], c[1], c[2], c[3]);
  }
  vtkNew<vtkPiecewiseFunction> opacity;
  for (const auto& o : tf.Opacities)
  {
    opacity->AddPoint(o[0], o[1]);
  }
  vtkNew<vtkVolumeProperty> property;
  property->SetColor(colour);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(tf.UnitDistance);
  return property;
}

// The paper's picture for the Spheres field: a red core seen through a translucent blue shell.
inline TransferFunction SpheresTF()
{
  TransferFunction tf;
  tf.Colours = { { 0.0, 0.0, 0.0, 0.0 }, { 0.5, 0.15, 0.3, 1.0 }, { 1.0, 1.0, 0.15, 0.1 } };
  tf.Opacities = { { 0.0, 0.0 }, { 0.2, 0.0 }, { 0.5, 0.12 }, { 0.75, 0.05 }, { 1.0, 0.95 } };
  tf.UnitDistance = 0.1;
  return tf;
}

// One colour per puzzle piece of the Sandwich field (piece / max(pieces - 1, 1)), all fairly
// opaque: interleaved slabs must occlude each other in the right order.
inline TransferFunction SandwichTF(int pieces)
{
  static const double palette[8][3] = { { 0.9, 0.1, 0.1 }, { 0.1, 0.8, 0.1 }, { 0.1, 0.2, 0.9 },
    { 0.9, 0.8, 0.1 }, { 0.8, 0.1, 0.8 }, { 0.1, 0.8, 0.8 }, { 0.9, 0.5, 0.1 }, { 0.6, 0.6, 0.6 } };
  TransferFunction tf;
  tf.Colours.clear();
  const double denominator = std::max(pieces - 1, 1);
  for (int p = 0; p < pieces; ++p)
  {
    const double* c = palette[p % 8];
    tf.Colours.push_back({ p / denominator, c[0], c[1], c[2] });
  }
  tf.Opacities = { { 0.0, 0.6 }, { 1.0, 0.6 } };
  tf.UnitDistance = 0.1;
  return tf;
}

// Smooth colour and opacity ramps over [0,1] that show every part of a smooth field.
inline TransferFunction RampTF()
{
  TransferFunction tf;
  tf.Colours = { { 0.0, 0.1, 0.2, 1.0 }, { 0.5, 0.9, 0.9, 0.2 }, { 1.0, 1.0, 0.1, 0.0 } };
  tf.Opacities = { { 0.0, 0.02 }, { 0.4, 0.1 }, { 1.0, 0.6 } };
  tf.UnitDistance = 0.2;
  return tf;
}

// Blue (min) through white to red (max), opacity rising from 0.05 to 0.6: any field shows.
inline TransferFunction BlueToRedTF(double min, double max, double unitDistance)
{
  TransferFunction tf;
  tf.Min = min;
  tf.Max = max;
  tf.Colours = { { min, 0.2, 0.3, 1.0 }, { 0.5 * (min + max), 0.9, 0.9, 0.9 },
    { max, 1.0, 0.2, 0.1 } };
  tf.Opacities = { { min, 0.05 }, { max, 0.6 } };
  tf.UnitDistance = unitDistance;
  return tf;
}

// The real wind data (U_mag): the buildings' wakes (nearly still air) in blue, the fast
// stream above in red.
inline TransferFunction WindTF()
{
  TransferFunction tf;
  tf.Min = 0;
  tf.Max = 20;
  tf.Colours = { { 0.0, 0.23, 0.30, 0.75 }, { 10.0, 0.87, 0.87, 0.87 },
    { 20.0, 0.71, 0.02, 0.15 } };
  tf.Opacities = { { 0.0, 0.5 }, { 2.0, 0.15 }, { 5.0, 0.0 }, { 12.0, 0.0 }, { 16.0, 0.03 },
    { 20.0, 0.2 } };
  tf.UnitDistance = 5.0;
  return tf;
}

// The core ray marcher's table of colour and opacity ramps over [0,1], 256 entries, for tests
// that bypass VTK. transparentBelow: nothing below 0.2, so that transparent samples sit inside
// runs and whole runs can be transparent.
inline apc::TransferTable RampTable(double spacing, bool transparentBelow)
{
  const int n = 256;
  std::vector<std::array<float, 3>> colours(n);
  std::vector<double> opacities(n);
  for (int i = 0; i < n; ++i)
  {
    const double s = i / (n - 1.0);
    colours[i] = { static_cast<float>(s), static_cast<float>(0.3 + 0.5 * s * (1 - s)),
      static_cast<float>(1 - s) };
    opacities[i] = (transparentBelow && s < 0.2) ? 0.0 : 0.02 + 0.5 * (s - 0.2) * (s - 0.2);
  }
  return apc::TransferTable(0.0, 1.0, colours, opacities, spacing, 0.1);
}

} // namespace apctest

#endif
