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
#include "apcCompositeFrame.h"
#include "apcFixedPointMoments.h"
#include "apcFrameEngine.h"
#include "apcResolve.h"

#include "vtkCommunicator.h"
#include "vtkMultiProcessController.h"

#include "apcOpaqueBins.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

namespace apc
{
namespace
{
// The packed copies of a band are made and summed this many pixels at a time (~80 MB of
// temporaries at 4 moments), so that they stay a bounded size whatever the band size; a
// 1024^2 frame still sends each buffer in one message.
constexpr size_t kChunkPixels = size_t(1) << 20;

// Sums the marked tiles of an image over all processes, in precision T: onto every process
// (allreduce) or onto the display process (reduce). Returns the bytes this process sent.
template <class T>
double SumTiles(const ProcessGroup& group, const TileGrid& tiles,
  const std::vector<unsigned char>& mask, std::vector<double>& image, int components,
  bool everywhere, FrameRecord& record)
{
  const std::vector<size_t> chunks = tiles.Chunks(mask, kChunkPixels);
  double bytes = 0;
  for (size_t c = 0; c + 1 < chunks.size(); ++c)
  {
    const size_t first = chunks[c];
    const size_t last = chunks[c + 1];
    const vtkIdType count = static_cast<vtkIdType>(tiles.PixelsIn(mask, first, last) * components);
    if (count == 0)
    {
      continue;
    }
    std::vector<T> send(count);
    std::vector<T> received(count);
    tiles.Pack(mask, image.data(), components, send.data(), first, last);
    group.Collective(everywhere ? "allreduce" : "reduce",
      [&]
      {
        if (everywhere)
        {
          group.Controller->AllReduce(send.data(), received.data(), count, vtkCommunicator::SUM_OP);
        }
        else
        {
          group.Controller->Reduce(
            send.data(), received.data(), count, vtkCommunicator::SUM_OP, group.Display);
        }
      });
    if (everywhere || group.IsDisplay())
    {
      tiles.Unpack(mask, received.data(), components, image.data(), first, last);
    }
    bytes += static_cast<double>(sizeof(T)) * count;
    ++record.MessagesSent;
  }
  return bytes;
}

// The global moments of the marked tiles onto every process, through fixed point: a MAX
// allreduce of each pixel's exponent byte, then a SUM allreduce of the int32 codes.
double SumMomentsInFixedPoint(const ProcessGroup& group, const TileGrid& tiles,
  const std::vector<unsigned char>& mask, std::vector<double>& moments, int stride,
  FrameRecord& record)
{
  const std::vector<size_t> chunks = tiles.Chunks(mask, kChunkPixels);
  const size_t pixels = tiles.PixelsIn(mask);
  std::vector<unsigned char> exponents(pixels);
  std::vector<double> packed;
  for (size_t c = 0, offset = 0; c + 1 < chunks.size(); ++c)
  {
    packed.resize(tiles.PixelsIn(mask, chunks[c], chunks[c + 1]) * stride);
    tiles.Pack(mask, moments.data(), stride, packed.data(), chunks[c], chunks[c + 1]);
    for (size_t p = 0; p < packed.size() / stride; ++p)
    {
      exponents[offset + p] = fixedpoint::ExponentByte(packed[p * stride]);
    }
    offset += packed.size() / stride;
  }
  std::vector<unsigned char> agreed(pixels);
  group.Collective("allreduce",
    [&]
    {
      group.Controller->AllReduce(
        exponents.data(), agreed.data(), static_cast<vtkIdType>(pixels), vtkCommunicator::MAX_OP);
    });
  exponents = std::vector<unsigned char>();
  ++record.MessagesSent;

  const int headroom = fixedpoint::HeadroomBits(group.Processes);
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
    packed.resize(count * stride);
    tiles.Pack(mask, moments.data(), stride, packed.data(), first, last);
    std::vector<int32_t> codes(packed.size(), 0);
    for (size_t p = 0; p < count; ++p)
    {
      const unsigned char e = agreed[offset + p];
      if (e)
      {
        const double scale = fixedpoint::Scale(e, headroom);
        for (int k = 0; k < stride; ++k)
        {
          codes[p * stride + k] = fixedpoint::Encode(packed[p * stride + k], scale, headroom);
        }
      }
    }
    std::vector<int32_t> sums(codes.size());
    group.Collective("allreduce",
      [&]
      {
        group.Controller->AllReduce(
          codes.data(), sums.data(), static_cast<vtkIdType>(codes.size()), vtkCommunicator::SUM_OP);
      });
    ++record.MessagesSent;
    for (size_t p = 0; p < count; ++p)
    {
      const unsigned char e = agreed[offset + p];
      const double scale = e ? fixedpoint::Scale(e, headroom) : 1.0;
      for (int k = 0; k < stride; ++k)
      {
        packed[p * stride + k] = fixedpoint::Decode(sums[p * stride + k], scale);
      }
    }
    tiles.Unpack(mask, packed.data(), stride, moments.data(), first, last);
    offset += count;
    bytes += static_cast<double>(sizeof(int32_t) * codes.size());
  }
  return bytes;
}

// The union of every process's covered tiles, on every process.
std::vector<unsigned char> AgreeOnTiles(const ProcessGroup& group, const TileGrid& tiles,
  const std::vector<double>& moments, int stride, FrameRecord& record)
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

// Saturating sums of opaque profiles (apcOpaqueBins.h): exact and order-independent.
class SaturatingProfileSum : public vtkCommunicator::Operation
{
public:
  void Function(const void* a, void* b, vtkIdType length, int) override
  {
    AddProfiles(static_cast<uint16_t*>(b), static_cast<const uint16_t*>(a), length);
  }
  int Commutative() override { return 1; }
};

// With Stop Where Opaque: every volume's opaque profile summed, over the covered tiles of
// every process (one allreduce of OpaqueBins::kBins 16-bit values per pixel), then each
// volume's own moments (own[e], or moments with one volume) cut where the sum is opaque and
// summed into moments. Every process makes the same calls: the setting is the volume's.
void CutWhereOpaque(const ProcessGroup& group, const CompositeFrame& frame, const RowBand& band,
  const TileGrid& tiles, const std::vector<unsigned char>& covered,
  std::vector<std::vector<double>>& own, std::vector<double>& moments, FrameRecord& record)
{
  constexpr int bins = OpaqueBins::kBins;
  const size_t pixels = moments.size() / (frame.Moments.Moments + 1);
  // One volume's profile is this process's own (no copy); several are summed.
  const std::vector<uint16_t>& first = frame.Engines.front()->GetOpaqueProfile();
  const bool single = frame.Engines.size() == 1 && first.size() == pixels * bins;
  std::vector<uint16_t> profile(single ? 0 : pixels * bins, 0);
  for (size_t e = 0; !single && e < frame.Engines.size(); ++e)
  {
    const std::vector<uint16_t>& volume = frame.Engines[e]->GetOpaqueProfile();
    AddProfiles(profile.data(), volume.data(), std::min(volume.size(), profile.size()));
  }
  const uint16_t* mine = single ? first.data() : profile.data();
  const size_t count = tiles.PixelsIn(covered) * bins;
  if (group.Parallel && count > 0)
  {
    std::vector<uint16_t> send(count);
    std::vector<uint16_t> received(count);
    tiles.Pack(covered, mine, bins, send.data());
    profile.assign(pixels * bins, 0); // the uncovered tiles have no samples anywhere
    mine = profile.data();
    SaturatingProfileSum sum;
    group.Collective("profile",
      [&]
      {
        group.Controller->AllReduce(
          send.data(), received.data(), static_cast<vtkIdType>(count), &sum);
      });
    tiles.Unpack(covered, received.data(), bins, profile.data());
    record.BytesSent += static_cast<double>(sizeof(uint16_t) * count);
    ++record.MessagesSent;
  }
  record.Clock.Lap("profile");
  for (size_t e = 0; e < frame.Engines.size(); ++e)
  {
    if (!frame.Engines[e]->StopsWhereOpaque(frame.Moments))
    {
      continue;
    }
    frame.Engines[e]->ApplyOpaqueCut(
      frame.Moments, mine, own.empty() ? moments.data() : own[e].data(), band);
  }
  if (!own.empty())
  {
    std::fill(moments.begin(), moments.end(), 0.0);
    for (const std::vector<double>& volume : own)
    {
      std::transform(volume.begin(), volume.end(), moments.begin(), moments.begin(),
        [](double a, double b) { return a + b; });
    }
  }
  record.Clock.Lap("cut");
}

// Whether some pixel's absorbance (b0) reaches absorbance.
bool AnyPixelReaches(const std::vector<double>& moments, int stride, double absorbance)
{
  for (size_t at = 0; at < moments.size(); at += static_cast<size_t>(stride))
  {
    if (moments[at] >= absorbance)
    {
      return true;
    }
  }
  return false;
}

// A band's pass 1 into moments (zeroed), the tiles' agreement (covered), the opaque cut if
// stops, and the moments' allreduce; ownCovered: the pixels this process's volumes cover.
void PassOne(const ProcessGroup& group, const CompositeFrame& frame, const RowBand& band,
  const TileGrid& tiles, bool stops, std::vector<double>& moments,
  std::vector<unsigned char>& covered, vtkIdType& ownCovered, FrameRecord& record)
{
  const MomentParameters& parameters = frame.Moments;
  const int stride = parameters.Moments + 1;
  const size_t pixels = moments.size() / stride;
  // The cut needs each volume's own moments: several volumes keep them apart until then.
  std::vector<std::vector<double>> own(
    stops && frame.Engines.size() > 1 ? frame.Engines.size() : 0);
  for (size_t e = 0; e < frame.Engines.size(); ++e)
  {
    if (own.empty())
    {
      frame.Engines[e]->RenderMoments(parameters, moments.data(), band);
      continue;
    }
    own[e].assign(pixels * stride, 0.0);
    frame.Engines[e]->RenderMoments(parameters, own[e].data(), band);
    std::transform(own[e].begin(), own[e].end(), moments.begin(), moments.begin(),
      [](double a, double b) { return a + b; });
  }
  record.Clock.Lap("pass1");
  ownCovered = 0;
  for (size_t p = 0; p < pixels; ++p)
  {
    ownCovered += moments[p * stride] > 0.0 ? 1 : 0;
  }

  // The mask's allreduce is where a process waits for the slowest one's pass 1 (its wait);
  // the moments' allreduce after it is nearly all transfer.
  covered = AgreeOnTiles(group, tiles, moments, stride, record);
  record.Clock.Lap("tiles");
  if (stops)
  {
    CutWhereOpaque(group, frame, band, tiles, covered, own, moments, record);
  }
  if (group.Parallel && tiles.Tiles() > 0)
  {
    record.BytesSent += frame.Settings.CompositeInDouble
      ? SumTiles<double>(group, tiles, covered, moments, stride, true, record)
      : SumMomentsInFixedPoint(group, tiles, covered, moments, stride, record);
  }
  record.Clock.Lap("allreduce");
}

// One band of rows of the frame (all of it unless the frame is large): pass 1, the tiles'
// agreement, the opaque cut, the moments' allreduce, pass 2 and the colour sums' reduce; the
// display process resolves the band into result at its rows.
void CompositeBand(const ProcessGroup& group, const CompositeFrame& frame, const RowBand& band,
  FrameRecord& record, FrameResult& result)
{
  const bool inDouble = frame.Settings.CompositeInDouble;
  const MomentParameters& parameters = frame.Moments;
  const int stride = parameters.Moments + 1;
  const int width = frame.RectWidth();
  const size_t pixels = static_cast<size_t>(width) * (band.J1 - band.J0);
  const size_t offset = static_cast<size_t>(width) * band.J0; // of the band in the frame
  const TileGrid tiles(width, 0, 0, width, band.J1 - band.J0);
  const bool exchange = group.Parallel && tiles.Tiles() > 0;

  // Agreed, not this process's own volumes: a process without volumes (or with the stop off
  // where others have it on) still joins the profile's allreduce.
  const bool stopping = frame.StopsWhereOpaque && parameters.Resolve != ResolveMode::Hybrid;
  bool stops = stopping && !frame.TryWithoutOpaqueStop;
  std::vector<double> moments;
  std::vector<unsigned char> covered;
  vtkIdType ownCovered = 0;
  // Without the stop, a pixel whose global absorbance reaches the threshold (less a margin
  // for the wire's rounding) may be one the stop cuts.
  const double opaque = VolumeRayMarcher::kRecommendedOpaqueAbsorbance * (1 - 1e-6);
  for (;;)
  {
    for (FrameEngine* engine : frame.Engines)
    {
      engine->SetOpaqueStopActive(stops);
    }
    moments.assign(pixels * stride, 0.0);
    PassOne(group, frame, band, tiles, stops, moments, covered, ownCovered, record);
    // Such a band is marched again with the stop. The global moments are the same integer
    // sums on every process, so all decide alike.
    if (stops || !stopping || !AnyPixelReaches(moments, stride, opaque))
    {
      break;
    }
    stops = true;
    ++record.OpaqueStopRedone;
  }
  record.OpaqueStopSkipped += stopping && !stops ? 1 : 0;
  record.OwnCoveredPixels += ownCovered;
  record.Pixels += static_cast<vtkIdType>(tiles.PixelsIn(covered));
  for (size_t p = 0; p < pixels; ++p)
  {
    record.CoveredPixels += moments[p * stride] > 0.0 ? 1 : 0;
    record.OpaquePixels += moments[p * stride] >= opaque ? 1 : 0;
  }

  std::vector<double> colourSums(pixels * 4, 0.0);
  for (FrameEngine* engine : frame.Engines)
  {
    engine->RenderColour(parameters, moments.data(), colourSums.data(), band);
  }
  record.Clock.Lap("pass2");
  if (exchange)
  {
    record.BytesSent += inDouble
      ? SumTiles<double>(group, tiles, covered, colourSums, 4, false, record)
      : SumTiles<float>(group, tiles, covered, colourSums, 4, false, record);
  }
  record.Clock.Lap("reduce");

  if (!group.IsDisplay())
  {
    return;
  }
  float* rgba = result.RGBA.data() + 4 * offset;
  if (frame.KeepFloatImages)
  {
    ResolveImage(parameters.Resolve, pixels, moments.data(), stride, colourSums.data(), rgba);
    std::copy(moments.begin(), moments.end(), result.Moments.begin() + stride * offset);
    std::copy(colourSums.begin(), colourSums.end(), result.ColourSums.begin() + 4 * offset);
  }
  else
  {
    // Resolved into the colour sums' own memory: no third band-sized buffer.
    ResolveImageInPlace(parameters.Resolve, pixels, moments.data(), stride, colourSums.data());
    std::memcpy(rgba, colourSums.data(), sizeof(float) * 4 * pixels);
  }
  record.Clock.Lap("resolve");
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

void RunMomentCompositing(
  const ProcessGroup& group, const CompositeFrame& frame, FrameRecord& record, FrameResult& result)
{
  record.Pixels = 0;
  if (group.IsDisplay())
  {
    const size_t pixels = frame.RectPixels();
    result.RGBA.assign(4 * pixels, 0.0f);
    if (frame.KeepFloatImages)
    {
      result.Moments.assign(pixels * (frame.Moments.Moments + 1), 0.0);
      result.ColourSums.assign(pixels * 4, 0.0);
    }
  }
  // The same bands on every process: they follow from the agreed rectangle and band size.
  const size_t bandPixels = static_cast<size_t>(frame.Settings.MaxBandPixels);
  for (const RowBand& band : MomentBands(frame.RectWidth(), frame.RectHeight(), bandPixels))
  {
    CompositeBand(group, frame, band, record, result);
  }
  for (const FrameEngine* engine : frame.Engines)
  {
    record.Pass1Samples += engine->GetSampleCount() + engine->GetCutSampleCount();
    record.Pass2Samples += engine->GetColourSampleCount();
    record.Pass2Replayed += engine->GetReplayedSampleCount();
    record.Pass2Hidden += engine->GetHiddenSampleCount();
  }
}

} // namespace apc
