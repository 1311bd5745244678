// SPDX-License-Identifier: BSD-3-Clause
// APC mode (the paper's Sec. 3): pass 1, then the processes agree on the tiles any of them
// covers and sum only those tiles' moments onto every process (allreduce); pass 2, and the
// same tiles' colour sums are summed onto the display process (reduce), which resolves.
// Each process sums its own samples in double. On the wire, unless asked for double: the
// moments as 32-bit fixed point with a per-pixel scale agreed first (exact, order-independent
// sums; see apcFixedPointMoments.h for why not float), the colour sums in float (the paper's
// format; their rounding is not amplified). 4 moments: 1 + 20 + 16 bytes per covered pixel.
// A large frame runs all of this band by band (rows of the screen rectangle), so that the
// moment and colour buffers (72 bytes per pixel at 4 moments) are one band's size: at 8192^2
// the whole rectangle's would be ~4.8 GB per process.
#include "apcAloneBands.h"
#include "apcCompositeFrame.h"
#include "apcCoveredTiles.h"
#include "apcFixedPointMoments.h"
#include "apcFrameEngine.h"
#include "apcOpaqueBins.h"
#include "apcResolve.h"
#include "apcStageAgreement.h"
#include "apcTestFailures.h"
#include "apcWireMessages.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

namespace apc
{
using wire::Hold;
using wire::HoldAs;
using wire::InMessages;
using wire::MessageValues;

namespace
{
// The packed copies of a band are made and summed this many pixels at a time, so that they
// stay a bounded size whatever the band size; a 1024^2 frame still packs each buffer once.
constexpr size_t kChunkPixels = size_t(1) << 20;

// Sums the marked tiles of an image over all processes, in precision T (send and received:
// the wire's buffers): onto every process (allreduce) or onto the display process (reduce).
// Returns the bytes this process sent.
template <class T>
double SumTiles(const ProcessGroup& group, const TileGrid& tiles,
  const std::vector<unsigned char>& mask, double* image, int components, bool everywhere,
  size_t maxBytes, MomentBuffers& buffers, FrameRecord& record)
{
  const std::vector<size_t> chunks = tiles.Chunks(mask, kChunkPixels);
  double bytes = 0;
  for (size_t c = 0; c + 1 < chunks.size(); ++c)
  {
    const size_t first = chunks[c];
    const size_t last = chunks[c + 1];
    const size_t count = tiles.PixelsIn(mask, first, last) * components;
    if (count == 0)
    {
      continue;
    }
    // One message at a time through the wire's buffers: the same messages as packing the
    // chunk whole, in buffers of one message's size.
    const size_t step = std::min(count, MessageValues<T>(maxBytes));
    T* send = HoldAs<T>(buffers.WireSend, step);
    T* received = HoldAs<T>(buffers.WireReceived, step);
    const bool takesSum = everywhere || group.IsDisplay();
    PackedWalk packing(tiles, mask, first, last);
    PackedWalk unpacking(tiles, mask, first, last);
    const auto pack = [&](size_t length)
    {
      packing.NextSpans(length, components,
        [&](size_t start, size_t values, size_t at)
        {
          for (size_t v = 0; v < values; ++v)
          {
            send[at + v] = static_cast<T>(image[start + v]);
          }
        });
    };
    pack(step);
    group.Collective(everywhere ? "allreduce" : "reduce",
      [&]
      {
        InMessages<T>(count, maxBytes,
          [&](size_t offset, vtkIdType length)
          {
            if (offset > 0)
            {
              pack(static_cast<size_t>(length));
            }
            if (everywhere)
            {
              group.Controller->AllReduce(send, received, length, vtkCommunicator::SUM_OP);
            }
            else
            {
              group.Controller->Reduce(
                send, received, length, vtkCommunicator::SUM_OP, group.Display);
            }
            ++record.MessagesSent;
            if (takesSum)
            {
              unpacking.NextSpans(static_cast<size_t>(length), components,
                [&](size_t start, size_t values, size_t at)
                {
                  for (size_t v = 0; v < values; ++v)
                  {
                    image[start + v] = static_cast<double>(received[at + v]);
                  }
                });
            }
          });
      });
    bytes += static_cast<double>(sizeof(T) * count);
  }
  return bytes;
}

// The global moments of the marked tiles of moments (band pixels) onto every process, through
// fixed point: a MAX allreduce of each pixel's exponent byte, then a SUM allreduce of the
// int32 codes.
double SumMomentsInFixedPoint(const ProcessGroup& group, const TileGrid& tiles,
  const std::vector<unsigned char>& mask, double* moments, size_t band, int stride, size_t maxBytes,
  MomentBuffers& buffers, FrameRecord& record)
{
  const std::vector<size_t> chunks = tiles.Chunks(mask, kChunkPixels);
  const size_t pixels = tiles.PixelsIn(mask);
  // Each pixel's exponent byte straight from the image (a byte per pixel), then packed: the
  // moments themselves are packed once, below.
  unsigned char* all = Hold(buffers.Agreed, band); // agreed on below, in the same buffer
  for (size_t p = 0; p < band; ++p)
  {
    all[p] = fixedpoint::ExponentByte(moments[p * stride]);
  }
  unsigned char* exponents = Hold(buffers.Exponents, pixels);
  tiles.Pack(mask, all, 1, exponents);
  unsigned char* agreed = Hold(buffers.Agreed, pixels);
  group.Collective("allreduce",
    [&]
    {
      InMessages<unsigned char>(pixels, maxBytes,
        [&](size_t offset, vtkIdType length)
        {
          group.Controller->AllReduce(
            exponents + offset, agreed + offset, length, vtkCommunicator::MAX_OP);
          ++record.MessagesSent;
        });
    });

  const int headroom = fixedpoint::HeadroomBits(group.Processes);
  const double limit = fixedpoint::Limit(headroom);
  double bytes = static_cast<double>(pixels);
  for (size_t c = 0, offset = 0; c + 1 < chunks.size(); ++c)
  {
    const size_t first = chunks[c];
    const size_t last = chunks[c + 1];
    const size_t count = tiles.PixelsIn(mask, first, last);
    if (count == 0)
    {
      continue;
    }
    // Encoded straight from the image and decoded straight into it, one message at a time
    // through the wire's buffers (one message's size): no packed copy of the doubles, nor of
    // the whole chunk's codes (at 1024^2 40 MB and 2 x 20 MB a process, paged in afresh by a
    // first frame). The same messages, so the same sums, as coding the chunk whole.
    const size_t values = count * stride;
    const size_t step = std::min(values, MessageValues<int32_t>(maxBytes));
    int32_t* codes = HoldAs<int32_t>(buffers.WireSend, step);
    int32_t* sums = HoldAs<int32_t>(buffers.WireReceived, step);
    const auto each = [stride](size_t) { return static_cast<size_t>(stride); };
    PackedWalk encoding(tiles, mask, first, last);
    PackedWalk decoding(tiles, mask, first, last);
    const auto encode = [&](size_t length)
    {
      encoding.Next(length, each,
        [&](size_t pixel, size_t i, size_t k0, size_t k1, size_t at)
        {
          const unsigned char e = agreed[offset + i];
          const double scale = e ? fixedpoint::Scale(e, headroom) : 1.0;
          const double* in = moments + pixel * stride;
          for (size_t k = k0; k < k1; ++k)
          {
            codes[at + k - k0] = e ? fixedpoint::EncodeWithin(in[k], scale, limit) : 0;
          }
        });
    };
    encode(step);
    group.Collective("allreduce",
      [&]
      {
        InMessages<int32_t>(values, maxBytes,
          [&](size_t at, vtkIdType length)
          {
            if (at > 0)
            {
              encode(static_cast<size_t>(length));
            }
            group.Controller->AllReduce(codes, sums, length, vtkCommunicator::SUM_OP);
            ++record.MessagesSent;
            decoding.Next(static_cast<size_t>(length), each,
              [&](size_t pixel, size_t i, size_t k0, size_t k1, size_t from)
              {
                const unsigned char e = agreed[offset + i];
                const double scale = e ? fixedpoint::Scale(e, headroom) : 1.0;
                double* out = moments + pixel * stride;
                for (size_t k = k0; k < k1; ++k)
                {
                  out[k] = fixedpoint::Decode(sums[from + k - k0], scale);
                }
              });
          });
      });
    offset += count;
    bytes += static_cast<double>(sizeof(int32_t) * values);
  }
  return bytes;
}

// The union of every process's covered tiles, on every process.
std::vector<unsigned char> AgreeOnTiles(const ProcessGroup& group, const TileGrid& tiles,
  const double* moments, int stride, FrameRecord& record)
{
  std::vector<unsigned char> mine =
    tiles.Mark([&](size_t pixel) { return moments[pixel * stride] > 0.0; });
  if (!group.Parallel || mine.empty())
  {
    return mine;
  }
  std::vector<unsigned char> all(mine.size());
  group.Collective("tiles",
    [&]
    {
      group.Controller->AllReduce(
        mine.data(), all.data(), static_cast<vtkIdType>(mine.size()), vtkCommunicator::MAX_OP);
    });
  record.BytesSent += static_cast<double>(mine.size());
  ++record.MessagesSent;
  return all;
}

// The display process's band of the result, from the global moments and colour sums.
void ResolveBand(const CompositeFrame& frame, size_t offset, size_t pixels, double* moments,
  double* colourSums, FrameResult& result)
{
  const MomentParameters& parameters = frame.Moments;
  const int stride = parameters.Moments + 1;
  float* rgba = result.RGBA.data() + 4 * offset;
  if (frame.KeepFloatImages)
  {
    ResolveImage(parameters.Resolve, pixels, moments, stride, colourSums, rgba);
    std::copy_n(moments, pixels * stride, result.Moments.begin() + stride * offset);
    std::copy_n(colourSums, pixels * 4, result.ColourSums.begin() + 4 * offset);
  }
  else
  {
    // Resolved into the colour sums' own memory: no third band-sized buffer.
    ResolveImageInPlace(parameters.Resolve, pixels, moments, stride, colourSums);
    std::memcpy(rgba, colourSums, sizeof(float) * 4 * pixels);
  }
}

// Pass 1 of every volume into moments (the band's pixels, zero), and into own[e] too where
// own is not empty (one per volume); bound: the predicted last bins, or null.
void RenderPassOne(const CompositeFrame& frame, const RowBand& band, size_t pixels, double* moments,
  std::vector<std::vector<double>>& own, const uint8_t* bound)
{
  const int stride = frame.Moments.Moments + 1;
  for (size_t e = 0; e < frame.Engines.size(); ++e)
  {
    if (own.empty())
    {
      frame.Engines[e]->RenderMoments(frame.Moments, moments, band, bound);
      continue;
    }
    own[e].assign(pixels * stride, 0.0);
    frame.Engines[e]->RenderMoments(frame.Moments, own[e].data(), band, bound);
    std::transform(
      own[e].begin(), own[e].end(), moments, moments, [](double a, double b) { return a + b; });
  }
}

// Whether some pixel's absorbance (b0) of a band's moments reaches absorbance.
bool AnyPixelReaches(const double* moments, size_t pixels, int stride, double absorbance)
{
  for (size_t p = 0; p < pixels; ++p)
  {
    if (moments[p * stride] >= absorbance)
    {
      return true;
    }
  }
  return false;
}

// Sums a band's image (components per pixel) over the marked tiles of every process, in the
// wire's precision: onto every process (everywhere) or onto the display process.
void SumImage(const ProcessGroup& group, const CompositeFrame& frame, const TileGrid& tiles,
  const std::vector<unsigned char>& covered, double* image, int components, bool everywhere,
  MomentBuffers& buffers, FrameRecord& record)
{
  if (!group.Parallel || tiles.Tiles() == 0)
  {
    return;
  }
  const size_t maxBytes = static_cast<size_t>(frame.Settings.MaxMessageBytes);
  record.BytesSent += frame.Settings.CompositeInDouble
    ? SumTiles<double>(
        group, tiles, covered, image, components, everywhere, maxBytes, buffers, record)
    : SumTiles<float>(
        group, tiles, covered, image, components, everywhere, maxBytes, buffers, record);
}

// Grows every buffer of buffers that a band of pixels may use after its pass 1 (its sums over
// the processes, the opaque cut) to the most that band can ask of it, so that all of them are
// allocated inside pass 1's failure agreement and none between two later collectives (the
// later Holds then find them large enough). stopping: the band may stop where opaque.
void HoldBandBuffers(const ProcessGroup& group, const CompositeFrame& frame, size_t pixels,
  bool stopping, MomentBuffers& buffers)
{
  constexpr size_t bins = OpaqueBins::kBins;
  const size_t stride = static_cast<size_t>(frame.Moments.Moments + 1);
  Hold(buffers.Moments, pixels * stride);
  if (stopping && frame.Engines.size() > 1)
  {
    Hold(buffers.ProfileLocal, pixels * bins);
  }
  if (!group.Parallel)
  {
    return;
  }
  // The wire's buffers: one message of the largest sum (SumTiles, SumMomentsInFixedPoint,
  // SumProfiles), each at most a message of MaxMessageBytes (or one value).
  const bool inDouble = frame.Settings.CompositeInDouble;
  size_t perPixel = std::max(stride, size_t(4)) * (inDouble ? sizeof(double) : sizeof(float));
  if (stopping)
  {
    perPixel = std::max(perPixel, bins * sizeof(uint16_t));
  }
  const size_t message =
    std::max(static_cast<size_t>(frame.Settings.MaxMessageBytes), sizeof(double));
  Hold(buffers.WireSend, std::min(pixels * perPixel, message));
  Hold(buffers.WireReceived, std::min(pixels * perPixel, message));
  if (!inDouble)
  {
    Hold(buffers.Exponents, pixels);
    Hold(buffers.Agreed, pixels);
  }
  if (stopping)
  {
    Hold(buffers.SummarySend, pixels);
    Hold(buffers.SummarySum, pixels);
    Hold(buffers.Unresolved, pixels);
    if (frame.Engines.size() > 1)
    {
      Hold(buffers.Profile, pixels * bins);
    }
  }
}

// A band's pass 1 into moments (pixels * stride values, zeroed here), the tiles' agreement
// (covered), the opaque cut if stops, and the moments' allreduce; ownCovered: the pixels this
// process's volumes cover. False if some process's pass 1 failed (agreed, record.Failed set):
// every process leaves the band before its next collective. earlier: this process's failure
// in the band's work before it (its buffers), agreed here; pass 1 is then not marched.
bool PassOne(const ProcessGroup& group, const CompositeFrame& frame, const RowBand& band,
  const TileGrid& tiles, bool stops, size_t pixels, double* moments,
  std::vector<unsigned char>& covered, vtkIdType& ownCovered, MomentBuffers& buffers,
  FrameRecord& record, const std::string& earlier)
{
  const int stride = frame.Moments.Moments + 1;
  bool bounded = false;
  std::vector<std::vector<double>> own;
  // This process's work up to the tiles' allreduce (the prediction, pass 1 and its memory)
  // runs inside the frame's failure agreement.
  const std::string failure = !earlier.empty()
    ? earlier
    : CatchFailure(
        [&]
        {
          bounded = stops && PredictOpaqueBand(frame, band, pixels, buffers);
          std::fill_n(moments, pixels * stride, 0.0);
          // The cut needs each volume's own moments: several volumes keep them apart until then.
          own.resize(stops && frame.Engines.size() > 1 ? frame.Engines.size() : 0);
          RenderPassOne(
            frame, band, pixels, moments, own, bounded ? buffers.Bound.data() : nullptr);
        });
  record.Clock.Lap("pass1");
  // The agreement is where a process now waits for the slowest one's pass 1: in the tiles'
  // stage, as the mask's allreduce after it was.
  if (!AgreeOnStage(group, "tiles", "pass 1", failure, record))
  {
    record.Clock.Lap("tiles");
    return false;
  }
  ownCovered = 0;
  for (size_t p = 0; p < pixels; ++p)
  {
    ownCovered += moments[p * stride] > 0.0 ? 1 : 0;
  }

  // The mask's allreduce is where a process waits for the slowest one's pass 1 (its wait);
  // the moments' allreduce after it is nearly all transfer.
  covered = AgreeOnTiles(group, tiles, moments, stride, record);
  record.Clock.Lap("tiles");
  if (stops &&
    !CutWhereOpaque(
      group, frame, band, tiles, covered, own, moments, pixels, bounded, buffers, record))
  {
    record.Clock.Lap("cut");
    return false;
  }
  if (group.Parallel && tiles.Tiles() > 0 && !frame.Settings.CompositeInDouble)
  {
    record.BytesSent += SumMomentsInFixedPoint(group, tiles, covered, moments, pixels, stride,
      static_cast<size_t>(frame.Settings.MaxMessageBytes), buffers, record);
  }
  else
  {
    SumImage(group, frame, tiles, covered, moments, stride, true, buffers, record);
  }
  record.Clock.Lap("allreduce");
  return true;
}

// Lends one volume's pass 1 the colour sums' memory for its opaque profile, and takes it back
// once the band's cut is made, or when the band is left early: the engine outlives the buffers.
class ProfileInColourSums
{
public:
  ProfileInColourSums() = default;
  ~ProfileInColourSums() { this->Withdraw(); }
  // Lends engine (if any) the first bytes of colourSums (held, so it may throw).
  void Lend(FrameEngine* engine, std::vector<unsigned char>& colourSums, size_t bytes)
  {
    if (engine)
    {
      engine->LendOpaqueProfileMemory(Hold(colourSums, bytes), bytes);
      this->Engine = engine;
    }
  }
  ProfileInColourSums(const ProfileInColourSums&) = delete;
  ProfileInColourSums& operator=(const ProfileInColourSums&) = delete;
  void Withdraw()
  {
    if (this->Engine)
    {
      this->Engine->LendOpaqueProfileMemory(nullptr, 0);
      this->Engine = nullptr;
    }
  }

private:
  FrameEngine* Engine = nullptr;
};

// One band of rows of the frame (all of it unless the frame is large): pass 1, the tiles'
// agreement, the opaque cut, the moments' allreduce, pass 2 and the colour sums' reduce; the
// display process resolves the band into result at its rows.
// tryWithoutStop: pass 1 marches without the stop first (agreed: frame.TryWithoutOpaqueStop,
// or a probe that found no ray near opaque). False if some process's pass 1 or pass 2 failed
// (agreed, record.Failed set): every process gives the frame up.
bool CompositeBand(const ProcessGroup& group, const CompositeFrame& frame, const RowBand& band,
  bool tryWithoutStop, MomentBuffers& buffers, FrameRecord& record, FrameResult& result)
{
  const MomentParameters& parameters = frame.Moments;
  const int stride = parameters.Moments + 1;
  const int width = frame.RectWidth();
  const size_t pixels = static_cast<size_t>(width) * (band.J1 - band.J0);
  const TileGrid tiles(width, 0, 0, width, band.J1 - band.J0);

  // Agreed, not this process's own volumes: a process without volumes (or with the stop off
  // where others have it on) still joins the profile's allreduce.
  const bool stopping = frame.StopsWhereOpaque && parameters.Resolve != ResolveMode::Hybrid;
  bool stops = stopping && !tryWithoutStop;
  std::vector<unsigned char> covered;
  vtkIdType ownCovered = 0;
  // Without the stop, a pixel whose global absorbance reaches the threshold (less a margin
  // for the wire's rounding) may be one the stop cuts.
  const double opaque = VolumeRayMarcher::kRecommendedOpaqueAbsorbance * (1 - 1e-6);
  // One volume's pass 1 makes its opaque profile in the colour sums' memory, idle until pass
  // 2 (after the cut): a first frame pages in one band-sized buffer less (32 MB a process at
  // 1024^2, the profile's 16 bins of 2 bytes as the colour sums' 4 doubles).
  const size_t sharedBytes =
    pixels * std::max(4 * sizeof(double), OpaqueBins::kBins * sizeof(uint16_t));
  ProfileInColourSums lent;
  double* moments = nullptr;
  // The band's buffers, agreed on with its first pass 1.
  std::string failure = CatchFailure(
    [&]
    {
      ThrowIfFailingForTesting(FailurePoint::BandBuffers);
      HoldBandBuffers(group, frame, pixels, stopping, buffers);
      moments = buffers.Moments.data();
      lent.Lend(stopping && frame.Engines.size() == 1 ? frame.Engines.front() : nullptr,
        buffers.ColourSums, sharedBytes);
    });
  for (;;)
  {
    for (FrameEngine* engine : frame.Engines)
    {
      engine->SetOpaqueStopActive(stops);
      // One process with one volume: its own absorbance is the global one.
      engine->SetOpaqueStopAlone(!group.Parallel && frame.Engines.size() == 1);
    }
    if (!PassOne(group, frame, band, tiles, stops, pixels, moments, covered, ownCovered, buffers,
          record, failure))
    {
      return false;
    }
    // Such a band is marched again with the stop. The global moments are the same integer
    // sums on every process, so all decide alike.
    if (stops || !stopping || !AnyPixelReaches(moments, pixels, stride, opaque))
    {
      break;
    }
    stops = true;
    ++record.OpaqueStopRedone;
  }
  lent.Withdraw(); // the cut is made: the colour sums' now
  record.OpaqueStopSkipped += stopping && !stops ? 1 : 0;
  record.OwnCoveredPixels += ownCovered;
  record.Pixels += static_cast<vtkIdType>(tiles.PixelsIn(covered));
  for (size_t p = 0; p < pixels; ++p)
  {
    record.CoveredPixels += moments[p * stride] > 0.0 ? 1 : 0;
    record.OpaquePixels += moments[p * stride] >= opaque ? 1 : 0;
  }

  double* colourSums = nullptr;
  failure = CatchFailure(
    [&]
    {
      colourSums = HoldAs<double>(buffers.ColourSums, pixels * 4);
      std::fill_n(colourSums, pixels * 4, 0.0);
      for (FrameEngine* engine : frame.Engines)
      {
        engine->RenderColour(parameters, moments, colourSums, band);
      }
    });
  record.Clock.Lap("pass2");
  // Where a process waits for the slowest one's pass 2: in the reduce's stage, as before.
  if (!AgreeOnStage(group, "reduce", "pass 2", failure, record))
  {
    record.Clock.Lap("reduce");
    return false;
  }
  SumImage(group, frame, tiles, covered, colourSums, 4, false, buffers, record);
  record.Clock.Lap("reduce");
  if (group.IsDisplay())
  {
    ResolveBand(frame, static_cast<size_t>(width) * band.J0, pixels, moments, colourSums, result);
    record.Clock.Lap("resolve");
  }
  return true;
}
}

std::vector<RowBand> MomentBands(int width, int height, size_t maxPixels)
{
  // Whole marcher tile rows, so that a tile is never split between bands (the wire's tiles,
  // of a size that divides the marcher's, then are whole too).
  constexpr int unit = VolumeRayMarcher::kTileSize;
  static_assert(VolumeRayMarcher::kTileSize % TileGrid::kDefaultTileSize == 0,
    "a band boundary must fall between the wire's tiles");
  std::vector<RowBand> bands;
  if (width < 1 || height < 1)
  {
    return bands;
  }
  const size_t unitPixels = static_cast<size_t>(width) * unit;
  const size_t units = (static_cast<size_t>(height) + unit - 1) / unit; // all the rows
  const int rows =
    static_cast<int>(std::min(units, std::max<size_t>(1, maxPixels / unitPixels))) * unit;
  for (int j0 = 0; j0 < height; j0 += rows)
  {
    bands.push_back({ j0, std::min(height, j0 + rows) });
  }
  return bands;
}

void RunMomentCompositing(const ProcessGroup& group, const CompositeFrame& frame,
  FrameRecord& record, FrameResult& result, MomentBuffers& buffers)
{
  record.Pixels = 0;
  if (group.IsDisplay())
  {
    // Reserved in the set-up's agreement (PrepareEngines): no allocation here.
    const size_t pixels = frame.RectPixels();
    result.RGBA.assign(4 * pixels, 0.0f);
    if (frame.KeepFloatImages)
    {
      result.Moments.assign(pixels * (frame.Moments.Moments + 1), 0.0);
      result.ColourSums.assign(pixels * 4, 0.0);
    }
  }
  // Several processes predict pass 1's cut from the last frame's if it was of the same image
  // (every process holds the same agreed cuts).
  std::swap(buffers.PreviousCuts, buffers.Cuts);
  buffers.Cuts.Valid = false;
  if (group.Parallel && frame.StopsWhereOpaque && frame.Moments.Resolve != ResolveMode::Hybrid)
  {
    buffers.Cuts.Begin({ frame.Width, frame.Height, frame.X0, frame.Y0, frame.ViewWidth,
                         frame.ViewHeight, frame.Interactive ? frame.Reduction() : 0 },
      frame.Rect.I0, frame.Rect.J0, frame.RectWidth(), frame.RectHeight());
  }
  // Without a previous cut for this image (a first frame), a probe of a few rays gives one.
  // Agreed: the cuts every process remembers, the frame's settings and its try without the stop.
  bool tryWithoutStop = frame.TryWithoutOpaqueStop;
  // A stage failed on some process (agreed): every process gives the frame up at the same
  // point, before any other collective, with nothing to blend.
  auto giveUp = [&]
  {
    buffers.Cuts.Valid = false;
    result.RGBA.clear();
    result.Moments.clear();
    result.ColourSums.clear();
  };
  if (buffers.Cuts.Valid && frame.Settings.OpaqueProbeStep > 0 && !frame.TryWithoutOpaqueStop &&
    !(buffers.PreviousCuts.Valid && buffers.PreviousCuts.Image == buffers.Cuts.Image))
  {
    record.Clock.Lap("pass1"); // the engines' set-up, in pass 1 as without the probe
    const ProbeResult probe = ProbeOpaqueCuts(group, frame, buffers, record);
    if (probe == ProbeResult::Failed)
    {
      giveUp();
      return;
    }
    // No probe ray near opaque: the frame is marched as one after a faint frame, without the
    // stop, and a band whose global absorbance reaches the threshold after all is marched again
    // with it (CompositeBand), so its image is the stop's. The double wire's sums may round
    // differently on each process: no retry decided from them (as for TryWithoutOpaqueStop).
    tryWithoutStop = probe == ProbeResult::NoneOpaque && !frame.Settings.CompositeInDouble;
  }
  // The same bands on every process: they follow from the agreed rectangle and band size.
  // One process has no collective to pay per band: its bands are small (apcAloneBands.h).
  size_t bandPixels = static_cast<size_t>(frame.Settings.MaxBandPixels);
  if (!group.Parallel)
  {
    int threads = 1;
    for (const FrameEngine* engine : frame.Engines)
    {
      threads = std::max(threads, engine->GetThreads());
    }
    bandPixels = AloneBandPixels(bandPixels, threads, VolumeRayMarcher::kTileSize);
  }
  static_assert(kAloneBandTilesPerThread >= VolumeRayMarcher::kTilesPerThreadWithoutStop,
    "one process's bands must keep its pass 1's tiles without the stop");
  for (const RowBand& band : MomentBands(frame.RectWidth(), frame.RectHeight(), bandPixels))
  {
    if (!CompositeBand(group, frame, band, tryWithoutStop, buffers, record, result))
    {
      giveUp();
      return;
    }
    ++record.Bands;
  }
  for (const FrameEngine* engine : frame.Engines)
  {
    record.Pass1Samples += engine->GetSampleCount() + engine->GetCutSampleCount();
    record.Pass2Samples += engine->GetColourSampleCount();
    record.Pass2Replayed += engine->GetReplayedSampleCount();
    record.Pass2Hidden += engine->GetHiddenSampleCount();
    record.OpaqueUnstoppedTiles += engine->GetUnstoppedTileCount();
  }
}

} // namespace apc
