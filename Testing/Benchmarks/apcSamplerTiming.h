// SPDX-License-Identifier: BSD-3-Clause
// The core ray marcher's own cost per sample, without the mapper around it: the mesh, camera
// and transfer function of a benchmark scene handed to apc::VolumeRayMarcher directly, pass 1
// (moments) and pass 2 (colour, replayed from pass 1's sample cache) timed separately in
// process CPU time with the marcher's recommended opaque stop on (off by default), the samples
// a ray skips once it is opaque counted against a run that
// marches them all, and the resolved image held against the exact ordered blend of every
// sample. The same source builds against a marcher that cannot stop rays (it then reports no
// hidden samples), so that one benchmark measures the code before and after side by side.
#ifndef apcSamplerTiming_h
#define apcSamplerTiming_h

#include <cmath>
#include <cstdint>
#include <vector>

class vtkRenderer;
class vtkUnstructuredGrid;
class vtkVolumeProperty;

namespace apcbench
{

struct SamplerTiming
{
  bool Valid = false;
  int64_t Cells = 0;
  int64_t Samples = 0;      // pass 1's samples (those in front of each ray's opaque point)
  int64_t AllSamples = 0;   // the same view marched without stopping (= Samples if it cannot)
  int64_t Pass2Samples = 0; // pass 2's samples: pass 1's visible ones (absorbance > 0)
  double CacheShare = NAN;  // share of pass 2's samples replayed from the cache
  // Share of pass 2's samples skipped behind the hidden depth of the global moments (0 where
  // the marcher cannot skip them).
  double Pass2HiddenShare = NAN;
  double Pass2HiddenShareUnstopped = NAN; // the same in the frame marched without the stop
  // Set-up once per data change, wall seconds: the whole conversion from VTK (Finalize
  // included) and CellMesh::Finalize alone (run again on the converted mesh).
  double MeshSeconds = NAN;
  double FinalizeSeconds = NAN;
  // Medians over the repeats, seconds: binning (SetView), pass 1, pass 2 (wall and CPU).
  double ViewSeconds = NAN;
  double Pass1Seconds = NAN;
  double Pass2Seconds = NAN;
  double Pass1Cpu = NAN;
  double Pass2Cpu = NAN;
  // Largest difference (any channel, premultiplied RGBA in [0,1]) of the resolved MBOIT image
  // from the exact ordered blend of all samples, and from the MBOIT image marched without
  // stopping (what stopping alone changes).
  double ErrorVsExact = NAN;
  double StopChange = NAN;
  double StopChangeShare = NAN; // share of pixels the stop changes by more than 1/255
  double ErrorVsExactAll = NAN; // ErrorVsExact of the image marched without stopping
  // Share of pixels farther from the exact blend with the stop than without by over 1/255.
  double WorseShare = NAN;
  // Largest difference of the exact blend with nearly affine cells sampled linearly from the
  // one with Newton in every non-affine cell (0 where the marcher has no linear inverse).
  double LinearChange = NAN;
  double Spacing = NAN; // the sample spacing used
  // The stop's threshold this row was marched with (+inf: no stop).
  double OpaqueAbsorbance = NAN;
  // The resolved image against the exact blend as evaluation's quality table compares them
  // (apc::CompareImages: premultiplied RGB over black, data range 1), with the stop and
  // marched without it.
  double PsnrVsExact = NAN;
  double SsimVsExact = NAN;
  double PsnrVsExactAll = NAN;
  double SsimVsExactAll = NAN;
  // Against the first threshold's image (TimeSamplerThresholds): the largest difference (any
  // channel) and the share of pixels farther from the exact blend than that image by over
  // 1/255 (0 and 0 for the first itself).
  double ChangeFromFirst = NAN;
  double WorseThanFirstShare = NAN;
  double MostWorseThanFirst = NAN; // the most any channel is farther from the exact blend
  // With compare: the resolved premultiplied RGBA (size x size, as the marcher's rows), and
  // the exact blend's on the first result only (for pictures to look at).
  std::vector<float> Image;
  std::vector<float> ExactImage;

  double HiddenShare() const
  {
    return this->AllSamples > 0 ? 1.0 - static_cast<double>(this->Samples) / this->AllSamples : NAN;
  }
  double Pass1NanosecondsPerSample() const { return 1e9 * this->Pass1Cpu / this->Samples; }
  double Pass2NanosecondsPerSample() const { return 1e9 * this->Pass2Cpu / this->Pass2Samples; }
};

// Marches grid's point scalars (the active ones) as renderer's camera sees them, through
// property's transfer function, at size x size with the given sample spacing (0: the mapper's
// default for these end weights, apc::DefaultSampleDistance) and 4 moments. compare: also render
// the exact and the non-stopping images for the two errors (one untimed frame each).
// linearTolerance: the marcher's linear-inverse tolerance in table bins (NaN: its default).
// withStop false: timed without the opaque stop, as the mapper renders by default (pass 2 then
// finds hidden depths where rays are opaque). endWeights: VolumeRayMarcher::EndWeightsMode (0 off,
// 1 all, 2 boundary). lanes: VolumeRayMarcher::SetSampleLanes (off: every pair in the scalar loop).
SamplerTiming TimeSampler(vtkUnstructuredGrid* grid, vtkRenderer* renderer,
  vtkVolumeProperty* property, int size, double spacing, int threads, int repeats, bool compare,
  double linearTolerance = NAN, bool withStop = true, int endWeights = 0, bool lanes = true);

// The same for each of several thresholds of the opaque stop (absorbance; +inf: no stop), one
// result each, in their order. Each repeat times every threshold in turn (A B C A B C ...), so
// that a machine whose load moves changes them alike; compare renders each threshold's image
// beside the exact and the unstopped ones, and compares each with the first threshold's.
std::vector<SamplerTiming> TimeSamplerThresholds(vtkUnstructuredGrid* grid, vtkRenderer* renderer,
  vtkVolumeProperty* property, int size, double spacing, int threads, int repeats, bool compare,
  double linearTolerance, const std::vector<double>& thresholds, int endWeights, bool lanes);

} // namespace apcbench

#endif
