// SPDX-License-Identifier: BSD-3-Clause
#include "apcSamplerTiming.h"

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcDefaultSpacing.h"
#include "apcDepthWarp.h"
#include "apcImageMetrics.h"
#include "apcRayCamera.h"
#include "apcResolve.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include "vtkCamera.h"
#include "vtkColorTransferFunction.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPointData.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolumeProperty.h"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <iostream>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace apcbench
{
namespace
{

double CpuSeconds()
{
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double WallSeconds()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double Median(std::vector<double> values)
{
  if (values.empty())
  {
    return NAN;
  }
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

// The marcher's opaque stop, where it has one: this benchmark also builds against the code
// from before it existed.
template <class M, class = void>
struct CanStop : std::false_type
{
};
template <class M>
struct CanStop<M, std::void_t<decltype(std::declval<M&>().SetOpaqueAbsorbance(1.0))>>
  : std::true_type
{
};
// One process, one mesh: the marcher's own profile is the cut's (where it knows that).
template <class M, class = void>
struct CanBeAlone : std::false_type
{
};
template <class M>
struct CanBeAlone<M, std::void_t<decltype(std::declval<M&>().SetOpaqueStopAlone(true))>>
  : std::true_type
{
};
template <class M>
void SetAlone(M& marcher)
{
  if constexpr (CanBeAlone<M>::value)
  {
    marcher.SetOpaqueStopAlone(true);
  }
  else
  {
    (void)marcher;
  }
}

template <class M>
bool SetStop(M& marcher, double absorbance)
{
  if constexpr (CanStop<M>::value)
  {
    marcher.SetOpaqueAbsorbance(absorbance);
    return true;
  }
  else
  {
    (void)marcher;
    (void)absorbance;
    return false;
  }
}
// The marcher's recommended stop (it is off by default), +inf where it has none.
template <class M>
double RecommendedStop()
{
  if constexpr (CanStop<M>::value)
  {
    return M::kRecommendedOpaqueAbsorbance;
  }
  else
  {
    return std::numeric_limits<double>::infinity();
  }
}

template <class M>
double GetStop(const M& marcher)
{
  if constexpr (CanStop<M>::value)
  {
    return marcher.GetOpaqueAbsorbance();
  }
  else
  {
    (void)marcher;
    return std::numeric_limits<double>::infinity();
  }
}

// Pass 2's share of samples skipped as hidden, where the marcher reports it.
template <class M, class = void>
struct ReportsHidden : std::false_type
{
};
template <class M>
struct ReportsHidden<M, std::void_t<decltype(std::declval<const M&>().GetLastHiddenShare())>>
  : std::true_type
{
};
template <class M>
double Pass2HiddenShare(const M& marcher)
{
  if constexpr (ReportsHidden<M>::value)
  {
    return marcher.GetLastHiddenShare();
  }
  else
  {
    (void)marcher;
    return 0.0;
  }
}

// The marcher's linear inverse of nearly affine cells, where it has one.
template <class M, class = void>
struct HasLinear : std::false_type
{
};
template <class M>
struct HasLinear<M, std::void_t<decltype(std::declval<M&>().SetLinearTolerance(1.0))>>
  : std::true_type
{
};
template <class M>
void SetLinearTolerance(M& marcher, double bins)
{
  if constexpr (HasLinear<M>::value)
  {
    marcher.SetLinearTolerance(bins);
  }
  else
  {
    (void)marcher;
    (void)bins;
  }
}

// The exact blend with the linear inverse's tolerance set to bins; false if there is none.
template <class M>
bool ExactWithLinearTolerance(
  M& marcher, const apc::TransferTable& table, double bins, std::vector<float>& rgba)
{
  if constexpr (HasLinear<M>::value)
  {
    const double kept = marcher.GetLinearTolerance();
    marcher.SetLinearTolerance(bins);
    marcher.RenderExact(table, rgba.data());
    marcher.SetLinearTolerance(kept);
    return true;
  }
  else
  {
    (void)marcher;
    (void)table;
    (void)bins;
    (void)rgba;
    return false;
  }
}

// The same table the mapper builds (apcFrameInputsFromVTK.cxx): colour and opacity sampled
// over the union of their ranges, 1024 entries.
apc::TransferTable MakeTable(vtkVolumeProperty* property, double spacing)
{
  constexpr int kEntries = 1024;
  vtkPiecewiseFunction* opacity = property->GetScalarOpacity(0);
  vtkColorTransferFunction* colour = property->GetRGBTransferFunction(0);
  double range[2];
  opacity->GetRange(range);
  range[0] = std::min(range[0], colour->GetRange()[0]);
  range[1] = std::max(range[1], colour->GetRange()[1]);
  std::vector<double> rgb(3 * kEntries);
  colour->GetTable(range[0], range[1], kEntries, rgb.data());
  std::vector<std::array<float, 3>> colours(kEntries);
  for (int i = 0; i < kEntries; ++i)
  {
    colours[i] = { static_cast<float>(rgb[3 * i]), static_cast<float>(rgb[3 * i + 1]),
      static_cast<float>(rgb[3 * i + 2]) };
  }
  std::vector<double> alphas(kEntries);
  opacity->GetTable(range[0], range[1], kEntries, alphas.data());
  return apc::TransferTable(
    range[0], range[1], colours, alphas, spacing, property->GetScalarOpacityUnitDistance(0));
}

apc::RayCamera MakeCamera(vtkRenderer* renderer, int size)
{
  vtkCamera* camera = renderer->GetActiveCamera();
  double clip[2];
  camera->GetClippingRange(clip);
  const double* p = camera->GetPosition();
  const double* f = camera->GetFocalPoint();
  const double* u = camera->GetViewUp();
  return apc::RayCamera({ p[0], p[1], p[2] }, { f[0], f[1], f[2] }, { u[0], u[1], u[2] },
    camera->GetViewAngle(), camera->GetParallelProjection() != 0, camera->GetParallelScale(), size,
    size, clip[0], clip[1]);
}

// Share of pixels (RGBA each) with a channel that differs by more than limit.
double ShareOver(const std::vector<float>& a, const std::vector<float>& b, double limit)
{
  size_t over = 0;
  for (size_t p = 0; p + 3 < a.size(); p += 4)
  {
    bool differs = false;
    for (size_t c = p; c < p + 4; ++c)
    {
      differs = differs || std::abs(a[c] - b[c]) > limit;
    }
    over += differs ? 1 : 0;
  }
  return a.empty() ? 0.0 : static_cast<double>(over) / (a.size() / 4);
}

double MaxDifference(const std::vector<float>& a, const std::vector<float>& b)
{
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i)
  {
    worst = std::max(worst, static_cast<double>(std::abs(a[i] - b[i])));
  }
  return worst;
}

// Share of pixels where a is farther from reference than b by more than limit (any channel).
double ShareWorse(const std::vector<float>& a, const std::vector<float>& b,
  const std::vector<float>& reference, double limit)
{
  size_t worse = 0;
  for (size_t p = 0; p + 3 < a.size(); p += 4)
  {
    bool differs = false;
    for (size_t c = p; c < p + 4; ++c)
    {
      differs = differs || std::abs(a[c] - reference[c]) > std::abs(b[c] - reference[c]) + limit;
    }
    worse += differs ? 1 : 0;
  }
  return a.empty() ? 0.0 : static_cast<double>(worse) / (a.size() / 4);
}

// Largest amount (any channel) by which a is farther from reference than b.
double MostWorse(
  const std::vector<float>& a, const std::vector<float>& b, const std::vector<float>& reference)
{
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i)
  {
    worst = std::max(
      worst, static_cast<double>(std::abs(a[i] - reference[i])) - std::abs(b[i] - reference[i]));
  }
  return worst;
}

// One MBOIT frame's resolved premultiplied RGBA (pass 1, pass 2, resolve); samples: pass 1's.
std::vector<float> MboitImage(apc::VolumeRayMarcher& marcher, const apc::TransferTable& table,
  const apc::LogDepthWarp& warp, size_t pixels, int64_t& samples)
{
  std::vector<double> moments(pixels * 5, 0.0);
  std::vector<double> sums(pixels * 4, 0.0);
  marcher.AccumulateMoments<4>(table, warp, moments.data());
  samples = marcher.GetLastSampleCount();
  marcher.AccumulateColour<4>(table, warp, moments.data(), apc::MomentSettings<4>(), sums.data());
  std::vector<float> rgba(pixels * 4);
  apc::ResolveImage(
    apc::ResolveMode::Renormalised, pixels, moments.data(), 5, sums.data(), rgba.data());
  return rgba;
}

// Evaluation's quality measure (docs/evaluation.md): premultiplied RGB over black, range 1.
apc::ImageComparison CompareOverBlack(
  const std::vector<float>& rgba, const std::vector<float>& reference, int size)
{
  const std::vector<float> a = apc::CompositeOverBackground(rgba.data(), size, size, { 0, 0, 0 });
  const std::vector<float> b =
    apc::CompositeOverBackground(reference.data(), size, size, { 0, 0, 0 });
  return apc::CompareImages(a.data(), b.data(), size, size, 3, 1.0, 1.0 / 255);
}
}

SamplerTiming TimeSampler(vtkUnstructuredGrid* grid, vtkRenderer* renderer,
  vtkVolumeProperty* property, int size, double spacing, int threads, int repeats, bool compare,
  double linearTolerance, bool withStop, int endWeights, bool lanes)
{
  const double stop =
    withStop ? RecommendedStop<apc::VolumeRayMarcher>() : std::numeric_limits<double>::infinity();
  return TimeSamplerThresholds(grid, renderer, property, size, spacing, threads, repeats, compare,
    linearTolerance, { stop }, endWeights, lanes)
    .front();
}

std::vector<SamplerTiming> TimeSamplerThresholds(vtkUnstructuredGrid* grid, vtkRenderer* renderer,
  vtkVolumeProperty* property, int size, double spacing, int threads, int repeats, bool compare,
  double linearTolerance, const std::vector<double>& thresholds, int endWeights, bool lanes)
{
  const size_t runs = thresholds.size();
  std::vector<SamplerTiming> results(runs);
  if (runs == 0)
  {
    return results;
  }
  SamplerTiming common;
  apc::CellMesh mesh;
  std::string message;
  double start = WallSeconds();
  if (!apc::CellMeshFromVTK(grid, grid->GetPointData()->GetScalars(), false, mesh, message))
  {
    std::cerr << "   sampler: " << message << "\n";
    return results;
  }
  common.MeshSeconds = WallSeconds() - start;
  start = WallSeconds();
  mesh.Finalize();
  common.FinalizeSeconds = WallSeconds() - start;
  if (endWeights == 2) // Sample End Weights = Boundary: the faces on the mesh's boundary
  {
    start = WallSeconds();
    const double cpu = CpuSeconds();
    mesh.FindBoundaryPlanes();
    std::cerr << "   sampler: boundary planes " << WallSeconds() - start << " s wall, "
              << CpuSeconds() - cpu << " s CPU\n";
  }
  common.Cells = mesh.GetNumberOfCells();
  const auto& b = mesh.GetBounds();
  if (!(spacing > 0))
  {
    // What the mapper takes for sample distance 0 with these end weights (one process).
    spacing = apc::DefaultSampleDistance(
      b.data(), static_cast<double>(common.Cells), mesh.GetCellVolume().Value(), endWeights != 0);
  }
  common.Spacing = spacing;
  const apc::TransferTable table = MakeTable(property, spacing);
  const apc::RayCamera camera = MakeCamera(renderer, size);
  double tmin = 0;
  double tmax = 0;
  camera.DistanceRange(b, tmin, tmax);
  const apc::LogDepthWarp warp(tmin, tmax);
  const size_t pixels = static_cast<size_t>(size) * size;

  apc::VolumeRayMarcher marcher;
  marcher.SetNumberOfThreads(threads);
  SetAlone(marcher);
  if (!std::isnan(linearTolerance))
  {
    SetLinearTolerance(marcher, linearTolerance);
  }
  marcher.SetEndWeightsMode(static_cast<apc::VolumeRayMarcher::EndWeightsMode>(endWeights));
  marcher.SetSampleLanes(lanes);
  marcher.SetMesh(&mesh);
  std::vector<std::vector<double>> view(runs), pass1(runs), pass2(runs), cpu1(runs), cpu2(runs);
  std::vector<double> moments(pixels * 5);
  std::vector<double> sums(pixels * 4);
  for (int r = 0; r < repeats; ++r)
  {
    for (size_t i = 0; i < runs; ++i)
    {
      SamplerTiming& result = results[i];
      SetStop(marcher, thresholds[i]);
      double wall = WallSeconds();
      marcher.SetView(camera, nullptr);
      view[i].push_back(WallSeconds() - wall);
      std::fill(moments.begin(), moments.end(), 0.0);
      std::fill(sums.begin(), sums.end(), 0.0);
      double cpu = CpuSeconds();
      wall = WallSeconds();
      marcher.AccumulateMoments<4>(table, warp, moments.data());
      pass1[i].push_back(WallSeconds() - wall);
      cpu1[i].push_back(CpuSeconds() - cpu);
      result.Samples = marcher.GetLastSampleCount();
      cpu = CpuSeconds();
      wall = WallSeconds();
      marcher.AccumulateColour<4>(
        table, warp, moments.data(), apc::MomentSettings<4>(), sums.data());
      pass2[i].push_back(WallSeconds() - wall);
      cpu2[i].push_back(CpuSeconds() - cpu);
      result.CacheShare = marcher.GetLastColourCacheShare();
      result.Pass2Samples = marcher.GetLastSampleCount();
      result.Pass2HiddenShare = Pass2HiddenShare(marcher);
    }
  }
  for (size_t i = 0; i < runs; ++i)
  {
    SamplerTiming& result = results[i];
    result.Cells = common.Cells;
    result.MeshSeconds = common.MeshSeconds;
    result.FinalizeSeconds = common.FinalizeSeconds;
    result.Spacing = common.Spacing;
    result.OpaqueAbsorbance = CanStop<apc::VolumeRayMarcher>::value
      ? thresholds[i]
      : std::numeric_limits<double>::infinity();
    result.ViewSeconds = Median(view[i]);
    result.Pass1Seconds = Median(pass1[i]);
    result.Pass2Seconds = Median(pass2[i]);
    result.Pass1Cpu = Median(cpu1[i]);
    result.Pass2Cpu = Median(cpu2[i]);
    result.AllSamples = result.Samples;
    result.Valid = true;
  }
  if (!compare)
  {
    return results;
  }
  std::vector<float> exact(pixels * 4, 0.0f);
  marcher.RenderExact(table, exact.data());
  std::vector<float> newton(pixels * 4, 0.0f);
  const double linearChange =
    ExactWithLinearTolerance(marcher, table, 0.0, newton) ? MaxDifference(exact, newton) : 0.0;
  newton = std::vector<float>();
  const bool canStop = SetStop(marcher, std::numeric_limits<double>::infinity());
  int64_t allSamples = 0;
  const std::vector<float> all = MboitImage(marcher, table, warp, pixels, allSamples);
  const double allHidden = Pass2HiddenShare(marcher);
  const apc::ImageComparison allQuality = CompareOverBlack(all, exact, size);
  for (size_t i = 0; i < runs; ++i)
  {
    SamplerTiming& result = results[i];
    SetStop(marcher, thresholds[i]);
    int64_t samples = 0;
    result.Image = MboitImage(marcher, table, warp, pixels, samples);
    const std::vector<float>& stopped = result.Image;
    result.ErrorVsExact = MaxDifference(stopped, exact);
    result.LinearChange = linearChange;
    const apc::ImageComparison quality = CompareOverBlack(stopped, exact, size);
    result.PsnrVsExact = quality.Psnr;
    result.SsimVsExact = quality.Ssim;
    result.PsnrVsExactAll = allQuality.Psnr;
    result.SsimVsExactAll = allQuality.Ssim;
    result.ErrorVsExactAll = result.ErrorVsExact;
    result.StopChange = 0;
    result.StopChangeShare = 0;
    result.WorseShare = 0;
    if (canStop)
    {
      result.AllSamples = allSamples;
      result.Pass2HiddenShareUnstopped = allHidden;
      result.StopChange = MaxDifference(stopped, all);
      result.StopChangeShare = ShareOver(stopped, all, 1.0 / 255);
      result.ErrorVsExactAll = MaxDifference(all, exact);
      result.WorseShare = ShareWorse(stopped, all, exact, 1.0 / 255);
    }
    const std::vector<float>& first = results.front().Image;
    result.ChangeFromFirst = MaxDifference(stopped, first);
    result.WorseThanFirstShare = ShareWorse(stopped, first, exact, 1.0 / 255);
    result.MostWorseThanFirst = MostWorse(stopped, first, exact);
  }
  results.front().ExactImage = std::move(exact);
  return results;
}

} // namespace apcbench
