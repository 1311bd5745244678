// What APC's compositing relies on, checked on the mapper and on the core ray marcher:
// - the image does not depend on the order of the cells or the numbering of the points;
// - the moment and colour sums of a split mesh add up to those of the whole mesh (the
//   MPI_Allreduce / MPI_Reduce of distributed APC), for puzzle pieces and for jagged splits
//   whose pieces interleave in depth, with every lattice sample taken exactly once;
// - the per-pixel segment counts of the gear-teeth pieces add up to the analytic count;
// - ghost cells (DUPLICATECELL, HIDDENCELL) render as if they were not there;
// - a ray that lies exactly in a face plane shared by two cells samples it once.

#include "apcTestGrids.h"
#include "apcTestImages.h"
#include "apcTestPuzzles.h"
#include "apcTestRender.h"

#include "apcCellMesh.h"
#include "apcCellMeshFromVTK.h"
#include "apcDepthWarp.h"
#include "apcMomentTransmittance.h"
#include "apcRayCamera.h"
#include "apcResolve.h"
#include "apcTransferTable.h"
#include "apcVolumeRayMarcher.h"

#include "vtkExtractCells.h"
#include "vtkIdList.h"
#include "vtkUnsignedCharArray.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

namespace
{
using apctest::Frame;

double Smooth(double x, double y, double z)
{
  return 0.5 + 0.45 * std::sin(2.1 * x + 0.4) * std::cos(1.7 * y - 0.3) * std::cos(1.3 * z + 0.2);
}

auto ModeSetter(int mode)
{
  return [mode](vtkAPCVolumeMapper* m)
  {
    m->SetMode(mode);
    m->SetSampleDistance(0.01);
  };
}

const char* ModeName(int mode)
{
  return mode == vtkAPCVolumeMapper::EXACT ? "EXACT" : "MBOIT";
}

//------------------------------------------------------------------------------
// Shuffle invariance.
//
// MBOIT: each pixel's moments and colour sums are sums over its samples; shuffling the cells
// changes only the order of the additions (the tiles take their cells in index order), so
// the images agree to double rounding of sums of a few hundred terms, printed as floats:
// 1e-5 is a generous bound on that (measured below; an order-dependent algorithm or a lost
// or duplicated sample would differ by ~1e-3 or more, the absorbance of one sample).
// EXACT: the same samples sorted by their unique lattice index, blended in the same order;
// only the interpolation of a sample lying within rounding of a face shared by two cells
// (whose plane may round differently with other point ids) could differ, by the field's
// change over ~1e-7: the same 1e-5 bound.
void ExpectShuffleInvariant(vtkUnstructuredGrid* grid, const apctest::TransferFunction& tf,
  const apctest::View& view, const char* name)
{
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    const Frame reference = apctest::Render(grid, ModeSetter(mode), tf, view);
    const double maxAlpha = apctest::MaxChannel(reference.RGBA, 4, 3);
    EXPECT_GT(maxAlpha, 0.2) << name << ": the scene must be visible";
    for (unsigned seed : { 1u, 2u, 3u })
    {
      auto shuffled = apctest::Shuffled(grid, seed);
      // The copy really is shuffled: most cells and points have moved.
      int cellsMoved = 0;
      int pointsMoved = 0;
      for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
      {
        cellsMoved += apctest::CellCentre(grid, c) != apctest::CellCentre(shuffled, c);
      }
      for (vtkIdType p = 0; p < grid->GetNumberOfPoints(); ++p)
      {
        double a[3];
        double b[3];
        grid->GetPoint(p, a);
        shuffled->GetPoint(p, b);
        pointsMoved += a[0] != b[0] || a[1] != b[1] || a[2] != b[2];
      }
      EXPECT_GT(cellsMoved, grid->GetNumberOfCells() / 2);
      EXPECT_GT(pointsMoved, grid->GetNumberOfPoints() / 2);
      const Frame other = apctest::Render(shuffled, ModeSetter(mode), tf, view);
      const double diff = apctest::MaxAbsDiff(reference.RGBA, other.RGBA);
      const double momentDiff = apctest::MaxAbsDiff(reference.Moments, other.Moments);
      std::cout << name << " " << ModeName(mode) << " seed " << seed
                << ": max |RGBA - shuffled RGBA| = " << diff
                << ", max |moments diff| = " << momentDiff << " (max alpha " << maxAlpha << ")\n";
      EXPECT_LE(diff, 1e-5) << name << " " << ModeName(mode) << " seed " << seed;
      if (mode == vtkAPCVolumeMapper::MBOIT)
      {
        // Moments are stored as floats; b0 is at most a few units here.
        EXPECT_LE(momentDiff, 1e-5) << name << " seed " << seed;
      }
    }
  }
}

TEST(VolumeMapperInvariance, ShuffledPuzzleRendersTheSame)
{
  auto grid = apctest::PuzzleGrid(vtkAPCPuzzleSource::SPHERES, 4, 4, 16);
  ExpectShuffleInvariant(grid, apctest::SpheresTF(), apctest::ObliqueView(96), "puzzle spheres");
}

TEST(VolumeMapperInvariance, ShuffledMixedCellsRenderTheSame)
{
  auto grid = apctest::MixedBlock(8, Smooth);
  std::cout << "mixed block: " << grid->GetNumberOfCells() << " cells\n";
  ExpectShuffleInvariant(grid, apctest::RampTF(), apctest::ObliqueView(96), "mixed cells");
}

//------------------------------------------------------------------------------
// Split sums on the core ray marcher, as distributed APC uses it.

struct Sums
{
  std::vector<double> Moments;
  std::vector<double> Colour;
  int64_t Samples = 0;
};

constexpr int kN = 4;

// The two passes over a set of meshes that together make the scene: moments summed over
// all of them, then each one's colour weighted by the summed moments (or by
// colourMoments if given), summed.
Sums MarchPieces(const std::vector<const apc::CellMesh*>& pieces, const apc::RayCamera& camera,
  const apc::TransferTable& table, const apc::LogDepthWarp& warp,
  const std::vector<double>* colourMoments = nullptr)
{
  const size_t pixels = static_cast<size_t>(camera.GetWidth()) * camera.GetHeight();
  Sums sums;
  sums.Moments.assign(pixels * (kN + 1), 0.0);
  sums.Colour.assign(pixels * 4, 0.0);
  apc::VolumeRayMarcher marcher;
  for (const apc::CellMesh* piece : pieces)
  {
    marcher.SetMesh(piece);
    marcher.SetView(camera, nullptr);
    marcher.AccumulateMoments<kN>(table, warp, sums.Moments.data());
    sums.Samples += marcher.GetLastSampleCount();
  }
  const apc::MomentSettings<kN> settings;
  const double* moments = colourMoments ? colourMoments->data() : sums.Moments.data();
  for (const apc::CellMesh* piece : pieces)
  {
    marcher.SetMesh(piece);
    marcher.SetView(camera, nullptr);
    marcher.AccumulateColour<kN>(table, warp, moments, settings, sums.Colour.data());
  }
  return sums;
}

struct SplitErrors
{
  double Moments = 0;          // max |b_k(pieces) - b_k(whole)| / b0(whole)
  double Colour = 0;           // max |C(pieces) - C(whole)| / W(whole), same moments
  double ColourSummed = 0;     // the same with each side's own moments in pass 2
  double RGBA = 0;             // resolved pixels, own moments
  double ExactNonAdditive = 0; // max |sum of the pieces' exact images - exact image|
  int Visible = 0;
};

double RelativeDiff(const std::vector<double>& a, const std::vector<double>& b, int stride,
  const std::vector<double>& norm, int normStride, int normOffset)
{
  double worst = 0;
  for (size_t p = 0; p < a.size() / stride; ++p)
  {
    const double scale = norm[p * normStride + normOffset];
    for (int k = 0; k < stride; ++k)
    {
      const double d = std::abs(a[p * stride + k] - b[p * stride + k]);
      if (scale > 0)
      {
        worst = std::max(worst, d / scale);
      }
      else if (d != 0 || !(d == d))
      {
        worst = std::numeric_limits<double>::infinity(); // an empty pixel must stay empty
      }
    }
  }
  return worst;
}

SplitErrors CompareSplit(vtkUnstructuredGrid* whole,
  const std::vector<vtkSmartPointer<vtkUnstructuredGrid>>& pieceGrids, const apc::RayCamera& camera,
  const char* name)
{
  const apc::CellMesh wholeMesh = apctest::ToMesh(whole);
  std::vector<apc::CellMesh> meshes;
  vtkIdType pieceCells = 0;
  for (const auto& g : pieceGrids)
  {
    meshes.push_back(apctest::ToMesh(g));
    pieceCells += g->GetNumberOfCells();
    EXPECT_GT(g->GetNumberOfCells(), 0) << name << ": every piece must own cells";
  }
  EXPECT_EQ(pieceCells, whole->GetNumberOfCells()) << name << ": the pieces must partition";
  std::vector<const apc::CellMesh*> pieces;
  for (const auto& m : meshes)
  {
    pieces.push_back(&m);
  }

  // What every rank shares: the camera, the transfer function, and the depth warp of the
  // whole data's bounds.
  const auto& b = wholeMesh.GetBounds();
  const double diagonal = std::sqrt(
    (b[1] - b[0]) * (b[1] - b[0]) + (b[3] - b[2]) * (b[3] - b[2]) + (b[5] - b[4]) * (b[5] - b[4]));
  const apc::TransferTable table = apctest::RampTable(diagonal / 300, true);
  double tmin = 0;
  double tmax = 0;
  camera.DistanceRange(b, tmin, tmax);
  const apc::LogDepthWarp warp(tmin, tmax);

  const Sums reference = MarchPieces({ &wholeMesh }, camera, table, warp);
  const Sums split = MarchPieces(pieces, camera, table, warp);
  const Sums splitSameMoments = MarchPieces(pieces, camera, table, warp, &reference.Moments);

  SplitErrors e;
  EXPECT_EQ(split.Samples, reference.Samples)
    << name << ": every lattice sample must be taken by exactly one piece";
  e.Moments = RelativeDiff(split.Moments, reference.Moments, kN + 1, reference.Moments, kN + 1, 0);
  e.Colour = RelativeDiff(splitSameMoments.Colour, reference.Colour, 4, reference.Colour, 4, 3);
  e.ColourSummed = RelativeDiff(split.Colour, reference.Colour, 4, reference.Colour, 4, 3);
  const size_t pixels = reference.Colour.size() / 4;
  for (size_t p = 0; p < pixels; ++p)
  {
    apc::ColourSums cs;
    apc::ColourSums cw;
    std::copy(split.Colour.begin() + 4 * p, split.Colour.begin() + 4 * p + 4, cs.Data());
    std::copy(reference.Colour.begin() + 4 * p, reference.Colour.begin() + 4 * p + 4, cw.Data());
    const apc::RGBA rs =
      apc::Resolve(apc::ResolveMode::Renormalised, cs, split.Moments[p * (kN + 1)]);
    const apc::RGBA rw =
      apc::Resolve(apc::ResolveMode::Renormalised, cw, reference.Moments[p * (kN + 1)]);
    for (int c = 0; c < 4; ++c)
    {
      e.RGBA = std::max(e.RGBA, std::abs(rs[c] - rw[c]));
    }
    e.Visible += rw[3] > 0.05;
  }

  // For the record: exact blending is not a sum over pieces.
  std::vector<float> exactWhole(4 * pixels, 0.f);
  std::vector<float> exactSum(4 * pixels, 0.f);
  apc::VolumeRayMarcher marcher;
  marcher.SetMesh(&wholeMesh);
  marcher.SetView(camera, nullptr);
  marcher.RenderExact(table, exactWhole.data());
  for (const apc::CellMesh* piece : pieces)
  {
    marcher.SetMesh(piece);
    marcher.SetView(camera, nullptr);
    marcher.RenderExact(table, exactSum.data());
  }
  e.ExactNonAdditive = apctest::MaxAbsDiff(exactWhole, exactSum);

  std::cout << name << " (" << pieceGrids.size() << " pieces, " << reference.Samples << " samples, "
            << e.Visible << " pixels with alpha > 0.05): moments rel. diff " << e.Moments
            << ", colour rel. diff (same moments) " << e.Colour
            << ", colour rel. diff (summed moments) " << e.ColourSummed
            << ", resolved RGBA max diff " << e.RGBA
            << "; EXACT images summed over pieces differ by " << e.ExactNonAdditive << "\n";
  EXPECT_GT(e.Visible, static_cast<int>(pixels) / 5) << name << ": the scene must be visible";
  // Moments: the same terms added in another order (per tile, per piece): a few hundred
  // terms with |z^k a| <= a give errors ~ 1e-14 b0; 1e-12 leaves room and still fails on any
  // lost, duplicated or differently warped sample (>= 1e-4 relative).
  EXPECT_LE(e.Moments, 1e-12) << name;
  // Colour with identical moments in pass 2: again only the order of the sums.
  EXPECT_LE(e.Colour, 1e-12) << name;
  // Colour with each side's own moments: T is reconstructed from moments that differ by
  // ~1e-15 relative; the reconstruction (an LDL^T solve of a biased Hankel matrix, eps =
  // 5e-7, and polynomial roots) amplifies that: measured up to 4e-13, so 1e-10 (250 times
  // that) still fails on any real difference (a lost sample changes W by >= 1e-4).
  EXPECT_LE(e.ColourSummed, 1e-10) << name;
  // The resolved pixels, alpha C / W: the same bound (measured ~1e-15, the ratio cancels).
  EXPECT_LE(e.RGBA, 1e-10) << name;
  return e;
}

TEST(VolumeMapperInvariance, PuzzlePiecesSumToTheWhole)
{
  const apc::RayCamera camera = apctest::ObliqueCamera(96);
  for (int k : { 2, 3, 5 })
  {
    auto whole = apctest::PuzzleGrid(vtkAPCPuzzleSource::SMOOTH, k, 2, 12);
    std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
    for (int p = 0; p < k; ++p)
    {
      pieces.push_back(apctest::PuzzlePiece(vtkAPCPuzzleSource::SMOOTH, k, 2, 12, p));
    }
    CompareSplit(whole, pieces, camera, ("puzzle K=" + std::to_string(k)).c_str());
  }
}

// Pieces as a graph partitioner leaves them: cells assigned by a hash of their id or by a
// noisy coordinate along the view direction (so each piece owns several disjoint depth
// layers), extracted with vtkExtractCells (each piece has its own, compacted point ids).
std::vector<vtkSmartPointer<vtkUnstructuredGrid>> JaggedPieces(
  vtkUnstructuredGrid* grid, int k, bool byHash)
{
  return apctest::SplitCells(grid, k,
    [grid, k, byHash](vtkIdType c)
    {
      if (byHash)
      {
        return static_cast<int>(apctest::CellHash(c) % k);
      }
      const auto x = apctest::CellCentre(grid, c);
      const double s =
        2.5 * (x[0] + 0.7 * x[1] + 0.9 * x[2]) + 0.35 * std::sin(9 * x[1] - 4 * x[0]);
      return static_cast<int>(std::floor(s * 1.7 + 100.0)) % k;
    });
}

TEST(VolumeMapperInvariance, JaggedPiecesSumToTheWhole)
{
  const apc::RayCamera camera = apctest::ObliqueCamera(96);
  auto mixed = apctest::MixedBlock(12, Smooth);
  auto puzzle = apctest::PuzzleGrid(vtkAPCPuzzleSource::SMOOTH, 3, 3, 12);
  for (auto* grid : { mixed.Get(), puzzle.Get() })
  {
    const std::string what = grid == mixed.Get() ? "mixed" : "puzzle";
    for (bool byHash : { true, false })
    {
      for (int k : { 2, 3, 5 })
      {
        auto pieces = JaggedPieces(grid, k, byHash);
        // The pieces must really interleave in depth: along most rays each piece is entered
        // more than once.
        int64_t segments = 0;
        int64_t covered = 0;
        for (const auto& piece : pieces)
        {
          const apc::CellMesh mesh = apctest::ToMesh(piece);
          apc::VolumeRayMarcher marcher;
          marcher.SetMesh(&mesh);
          marcher.SetView(camera, nullptr);
          std::vector<int32_t> counts(96 * 96, 0);
          marcher.CountSegments(counts.data());
          for (int32_t c : counts)
          {
            segments += c;
            covered += c > 0;
          }
        }
        const double perPiece = static_cast<double>(segments) / std::max<int64_t>(covered, 1);
        const std::string name =
          what + (byHash ? " hash" : " noisy layers") + " K=" + std::to_string(k);
        std::cout << name << ": mean segments per piece per covered ray " << perPiece << "\n";
        EXPECT_GT(perPiece, 1.5) << name << ": the pieces must interleave in depth";
        CompareSplit(grid, pieces, camera, name.c_str());
      }
    }
  }
}

//------------------------------------------------------------------------------
// Gear teeth seen along the slab axis: each puzzle piece owns SlabsPerPiece slabs separated
// by the other pieces' slabs, so each ray crosses SlabsPerPiece disjoint segments of each
// piece, K * SlabsPerPiece in all; the whole grid is one segment (adjacent slabs share
// their boundary planes exactly, whatever their point ids). Integer counts: exact.
TEST(VolumeMapperInvariance, GearTeethSegmentCounts)
{
  const int size = 24;
  const int slabs = 3;
  // Parallel, looking down -z, rays at |x|, |y| <= 0.9: every ray crosses every slab.
  const apc::RayCamera camera(
    { 0, 0, 5 }, { 0, 0, 0 }, { 0, 1, 0 }, 30.0, true, 0.9, size, size, 0.1, 100.0);
  for (int k : { 2, 3, 5 })
  {
    std::vector<int32_t> sum(size * size, 0);
    std::vector<int32_t> whole(size * size, 0);
    for (int p = 0; p < k; ++p)
    {
      auto grid = apctest::PuzzlePiece(vtkAPCPuzzleSource::SANDWICH, k, slabs, 4, p);
      const apc::CellMesh mesh = apctest::ToMesh(grid);
      apc::VolumeRayMarcher marcher;
      marcher.SetMesh(&mesh);
      marcher.SetView(camera, nullptr);
      std::vector<int32_t> counts(size * size, 0);
      marcher.CountSegments(counts.data());
      int wrong = 0;
      for (int32_t c : counts)
      {
        wrong += c != slabs;
      }
      EXPECT_EQ(wrong, 0) << "K=" << k << " piece " << p << ": pixels without " << slabs
                          << " segments";
      for (int i = 0; i < size * size; ++i)
      {
        sum[i] += counts[i];
      }
    }
    auto grid = apctest::PuzzleGrid(vtkAPCPuzzleSource::SANDWICH, k, slabs, 4);
    const apc::CellMesh mesh = apctest::ToMesh(grid);
    apc::VolumeRayMarcher marcher;
    marcher.SetMesh(&mesh);
    marcher.SetView(camera, nullptr);
    marcher.CountSegments(whole.data());
    const auto [sumMin, sumMax] = std::minmax_element(sum.begin(), sum.end());
    const auto [wholeMin, wholeMax] = std::minmax_element(whole.begin(), whole.end());
    std::cout << "gear teeth K=" << k << ", " << slabs << " slabs per piece: summed counts in ["
              << *sumMin << ", " << *sumMax << "] (expected " << k * slabs << "), whole grid in ["
              << *wholeMin << ", " << *wholeMax << "] (expected 1)\n";
    EXPECT_EQ(*sumMin, k * slabs);
    EXPECT_EQ(*sumMax, k * slabs);
    EXPECT_EQ(*wholeMin, 1);
    EXPECT_EQ(*wholeMax, 1);

    // The mapper's heatmap of the whole grid, the same view through VTK's camera.
    apctest::View view;
    view.ParallelScale = 0.9;
    view.Width = view.Height = size;
    const Frame frame = apctest::Render(
      grid,
      [](vtkAPCVolumeMapper* m)
      {
        m->SetComputeSegmentCount(true);
        m->SetSampleDistance(0.01);
      },
      {}, view);
    ASSERT_EQ(frame.SegmentCount.size(), static_cast<size_t>(size * size));
    const auto [mapperMin, mapperMax] =
      std::minmax_element(frame.SegmentCount.begin(), frame.SegmentCount.end());
    EXPECT_EQ(*mapperMin, 1) << "K=" << k;
    EXPECT_EQ(*mapperMax, 1) << "K=" << k;
  }
}

//------------------------------------------------------------------------------
// Ghost cells. The grid without them is built on the very same points (so the face planes,
// the mesh bounds, the cell order within tiles and hence every sum are the same) and,
// separately, with vtkExtractCells (compacted point ids). Both must match to rounding:
// 1e-6, a few float ulps of values <= 1 (measured 0 for the former).
void ExpectGhostsSkipped(vtkUnstructuredGrid* grid, unsigned char flag,
  const std::function<bool(vtkIdType)>& ghost, const apctest::TransferFunction& tf,
  const char* name)
{
  auto ghosted = vtkSmartPointer<vtkUnstructuredGrid>::New();
  ghosted->ShallowCopy(grid);
  vtkNew<vtkUnsignedCharArray> ghosts;
  ghosts->SetName(vtkDataSetAttributes::GhostArrayName());
  ghosts->SetNumberOfTuples(grid->GetNumberOfCells());
  vtkNew<vtkIdList> kept;
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    ghosts->SetValue(c, ghost(c) ? flag : 0);
    if (!ghost(c))
    {
      kept->InsertNextId(c);
    }
  }
  ghosted->GetCellData()->AddArray(ghosts);
  ASSERT_EQ(ghosted->GetCellGhostArray(), ghosts.Get());
  auto subset = apctest::CellSubset(grid, [&ghost](vtkIdType c) { return !ghost(c); });
  vtkNew<vtkExtractCells> extract;
  extract->SetInputData(grid);
  extract->SetCellList(kept);
  extract->Update();
  std::cout << name << ": " << grid->GetNumberOfCells() - kept->GetNumberOfIds() << " of "
            << grid->GetNumberOfCells() << " cells are ghosts\n";

  const auto view = apctest::ObliqueView(96);
  for (int mode : { vtkAPCVolumeMapper::MBOIT, vtkAPCVolumeMapper::EXACT })
  {
    const Frame withGhosts = apctest::Render(ghosted, ModeSetter(mode), tf, view);
    const Frame without = apctest::Render(subset, ModeSetter(mode), tf, view);
    const Frame extracted = apctest::Render(extract->GetOutput(), ModeSetter(mode), tf, view);
    const Frame all = apctest::Render(grid, ModeSetter(mode), tf, view);
    const double dSubset = apctest::MaxAbsDiff(withGhosts.RGBA, without.RGBA);
    const double dExtract = apctest::MaxAbsDiff(withGhosts.RGBA, extracted.RGBA);
    const double dAll = apctest::MaxAbsDiff(withGhosts.RGBA, all.RGBA);
    std::cout << name << " " << ModeName(mode) << ": max |ghosted - without ghosts| = " << dSubset
              << " (same points), " << dExtract
              << " (vtkExtractCells); vs. all cells drawn: " << dAll << "\n";
    EXPECT_LE(dSubset, 1e-6) << name << " " << ModeName(mode);
    EXPECT_LE(dExtract, 1e-6) << name << " " << ModeName(mode);
    // The ghosts are a visible part of the scene: drawing them changes the picture.
    EXPECT_GT(dAll, 0.05) << name << " " << ModeName(mode);
  }
}

TEST(VolumeMapperInvariance, DuplicateCellsAreSkipped)
{
  auto grid = apctest::PuzzleGrid(vtkAPCPuzzleSource::SPHERES, 4, 2, 16);
  auto* owner = grid->GetCellData()->GetArray("PuzzlePiece");
  ASSERT_NE(owner, nullptr);
  // One puzzle piece and, separately, half the cells by hash.
  ExpectGhostsSkipped(
    grid, vtkDataSetAttributes::DUPLICATECELL,
    [owner](vtkIdType c) { return owner->GetComponent(c, 0) == 1; }, apctest::SpheresTF(),
    "puzzle piece 1 DUPLICATECELL");
  ExpectGhostsSkipped(
    grid, vtkDataSetAttributes::DUPLICATECELL,
    [](vtkIdType c) { return apctest::CellHash(c) % 2 == 0; }, apctest::SpheresTF(),
    "half the cells DUPLICATECELL");
}

TEST(VolumeMapperInvariance, HiddenCellsAreSkipped)
{
  auto grid = apctest::MixedBlock(8, Smooth);
  ExpectGhostsSkipped(
    grid, vtkDataSetAttributes::HIDDENCELL,
    [grid](vtkIdType c) { return apctest::CellCentre(grid, c)[0] > 0.1; }, apctest::RampTF(),
    "mixed x > 0.1 HIDDENCELL");
}

//------------------------------------------------------------------------------
// A ray lying exactly in a face plane shared by two cells (denominator 0 in the ray/plane
// clip) must sample the volume once, not once per cell. This happens whenever a pixel centre
// is aligned with a mesh plane: an odd-sized parallel view centred on a block with a face
// at x = 0 puts the middle column of pixels in that plane, and the middle row in y = 0.
TEST(VolumeMapperInvariance, RayInASharedFacePlaneSamplesOnce)
{
  const double sigma = -std::log(0.8); // alpha_tf 0.2 per unit distance
  auto grid = apctest::HexBlock(4, [](double, double, double) { return 0.5; });
  for (int mode : { vtkAPCVolumeMapper::EXACT, vtkAPCVolumeMapper::MBOIT })
  {
    apctest::View view;
    view.Width = view.Height = 65; // pixel 32's centre is at x = 0 (y = 0) exactly
    const Frame frame = apctest::Render(grid, ModeSetter(mode), {}, view);
    // Parallel rays along -z through the block: L = 2 everywhere inside |x|, |y| < 1.
    const double expected = -std::expm1(-2 * sigma);
    // The lattice puts 200 +- 1 samples on the ray: alpha within exp(-2 sigma) *
    // (exp(sigma * 0.01) - 1) ~ 1.5e-3 of the closed form; 2e-3 allows that.
    const double tolerance = 2e-3;
    auto alpha = [&](int i, int j) { return frame.RGBA[4 * (j * view.Width + i) + 3]; };
    std::cout << ModeName(mode) << ": alpha off the planes " << alpha(20, 20) << ", in x = 0 "
              << alpha(32, 20) << ", in y = 0 " << alpha(20, 32) << ", on both " << alpha(32, 32)
              << "; expected " << expected << "\n";
    EXPECT_NEAR(alpha(20, 20), expected, tolerance) << ModeName(mode) << " off the planes";
    EXPECT_NEAR(alpha(32, 20), expected, tolerance) << ModeName(mode) << " ray in x = 0";
    EXPECT_NEAR(alpha(20, 32), expected, tolerance) << ModeName(mode) << " ray in y = 0";
    EXPECT_NEAR(alpha(32, 32), expected, tolerance) << ModeName(mode) << " ray in x = y = 0";
  }
}
}

namespace
{
// Pass 2 replays pass 1's cached samples (depth kept in float) and marches again the tiles
// the cache is off for or had no room for; every way must give the same colour sums.
TEST(VolumeMapperInvariance, CachedAndRemarchedPassTwoAgree)
{
  auto grid = apctest::MixedBlock(12,
    [](double x, double y, double z) { return 0.5 + 0.3 * std::sin(3 * x) * std::cos(2 * y) * z; });
  apc::CellMesh mesh = apctest::ToMesh(grid);
  const apc::RayCamera camera = apctest::ObliqueCamera(64);
  double tmin = 0;
  double tmax = 0;
  camera.DistanceRange(mesh.GetBounds(), tmin, tmax);
  const apc::LogDepthWarp warp(tmin, tmax);
  const apc::TransferTable table = apctest::RampTable(0.01, true);
  const size_t pixels = 64 * 64;
  std::vector<std::vector<double>> colours;
  for (size_t budget : { size_t(1) << 30, size_t(0), size_t(1000) })
  {
    apc::VolumeRayMarcher marcher;
    marcher.SetMaxSampleCacheBytes(budget);
    marcher.SetMesh(&mesh);
    marcher.SetView(camera, nullptr);
    std::vector<double> moments(pixels * 5, 0.0);
    std::vector<double> colour(pixels * 4, 0.0);
    marcher.AccumulateMoments<4>(table, warp, moments.data());
    marcher.AccumulateColour<4>(table, warp, moments.data(), {}, colour.data());
    // A whole cache, none, or the tiles that fit in 1000 bytes replayed and the rest marched.
    const double share = marcher.GetLastColourCacheShare();
    if (budget == 0)
    {
      EXPECT_EQ(share, 0.0);
    }
    else if (budget == 1000)
    {
      EXPECT_LT(share, 0.5) << "budget " << budget;
    }
    else
    {
      EXPECT_EQ(share, 1.0) << "budget " << budget;
    }
    colours.push_back(colour);
  }
  {
    // Lowering the budget between frames frees the cache: the next frame marches again.
    apc::VolumeRayMarcher marcher;
    marcher.SetMesh(&mesh);
    marcher.SetView(camera, nullptr);
    std::vector<double> moments(pixels * 5, 0.0);
    std::vector<double> colour(pixels * 4, 0.0);
    marcher.AccumulateMoments<4>(table, warp, moments.data());
    marcher.SetMaxSampleCacheBytes(0);
    marcher.AccumulateColour<4>(table, warp, moments.data(), {}, colour.data());
    EXPECT_EQ(marcher.GetLastColourCacheShare(), 0.0) << "the freed cache was replayed";
    EXPECT_EQ(colour, colours[1]) << "remarched after the budget fell: as without a cache";
  }
  double maxRelative = 0;
  double total = 0;
  for (size_t v = 0; v < colours[0].size(); ++v)
  {
    total += colours[0][v];
    for (size_t other : { 1, 2 })
    {
      maxRelative = std::max(maxRelative,
        std::abs(colours[0][v] - colours[other][v]) / std::max(1e-3, std::abs(colours[1][v])));
    }
  }
  std::cout << "cached vs re-marched pass 2: max relative difference " << maxRelative << "\n";
  EXPECT_GT(total, 1.0) << "something is rendered";
  // The cache keeps the warped depth in float (relative 6e-8); T(z) amplifies that a little.
  EXPECT_LE(maxRelative, 1e-5);
}
}

// A large frame is rendered band by band (rows), with band-sized buffers and the sample cache
// holding one band: each band's moments and colour sums must be exactly the rows of the whole
// image's, with and without the cache, and for Hybrid's own moments.
TEST(VolumeMapperInvariance, BandsAreTheRowsOfTheWholeImage)
{
  auto grid = apctest::MixedBlock(10,
    [](double x, double y, double z) { return 0.5 + 0.3 * std::sin(3 * x) * std::cos(2 * y) * z; });
  apc::CellMesh mesh = apctest::ToMesh(grid);
  // 56 rows: three whole bands of 16 and a last one of 8.
  const apc::RayCamera camera = apctest::ObliqueCamera(64).Cropped(0, 4, 64, 56);
  double tmin = 0;
  double tmax = 0;
  camera.DistanceRange(mesh.GetBounds(), tmin, tmax);
  const apc::LogDepthWarp warp(tmin, tmax);
  const apc::TransferTable table = apctest::RampTable(0.01, true);
  const int width = camera.GetWidth();
  const int height = camera.GetHeight();
  constexpr int rows = apc::VolumeRayMarcher::kTileSize;
  for (bool hybrid : { false, true })
  {
    for (size_t budget : { size_t(1) << 30, size_t(0) })
    {
      apc::VolumeRayMarcher marcher;
      marcher.SetMaxSampleCacheBytes(budget);
      marcher.SetMesh(&mesh);
      marcher.SetView(camera, nullptr);
      const size_t pixels = static_cast<size_t>(width) * height;
      std::vector<double> moments(pixels * 5, 0.0);
      std::vector<double> colour(pixels * 4, 0.0);
      marcher.AccumulateMoments<4>(table, warp, moments.data(), hybrid);
      marcher.AccumulateColour<4>(table, warp, moments.data(), {}, colour.data(), hybrid);
      const int64_t wholeSamples = marcher.GetLastSampleCount();
      int64_t bandSamples = 0;
      int bands = 0;
      for (int j0 = 0; j0 < height; j0 += rows, ++bands)
      {
        const apc::RowBand band{ j0, std::min(height, j0 + rows) };
        const size_t offset = static_cast<size_t>(width) * j0;
        const size_t n = static_cast<size_t>(width) * (band.J1 - band.J0);
        std::vector<double> bandMoments(n * 5, 0.0);
        std::vector<double> bandColour(n * 4, 0.0);
        marcher.AccumulateMoments<4>(table, warp, bandMoments.data(), hybrid, band);
        marcher.AccumulateColour<4>(
          table, warp, bandMoments.data(), {}, bandColour.data(), hybrid, band);
        bandSamples += marcher.GetLastSampleCount();
        EXPECT_TRUE(
          std::equal(bandMoments.begin(), bandMoments.end(), moments.begin() + 5 * offset))
          << "band from row " << j0 << (hybrid ? ", hybrid" : "") << ", budget " << budget;
        EXPECT_TRUE(std::equal(bandColour.begin(), bandColour.end(), colour.begin() + 4 * offset))
          << "band from row " << j0 << (hybrid ? ", hybrid" : "") << ", budget " << budget;
        EXPECT_EQ(marcher.GetLastColourCacheShare(), budget > 0 ? 1.0 : 0.0)
          << "each band's pass 2 replays that band's samples";
      }
      EXPECT_EQ(bands, 4);
      EXPECT_EQ(bandSamples, wholeSamples) << "every sample taken once, in one band";
      EXPECT_GT(wholeSamples, 1000);
    }
  }
}

// Memory follows the data's footprint on screen: a block seen small in a large
// view is rendered into buffers of its screen rectangle only, and the picture is the one the
// full view would show (nothing drawn outside the rectangle, the same pixels inside as a
// view that the block fills, shifted).
TEST(VolumeMapperInvariance, BuffersFollowTheDataFootprint)
{
  auto grid =
    apctest::MixedBlock(6, [](double x, double y, double z) { return 0.5 + 0.2 * x * y; });
  apctest::View wide;
  wide.Width = wide.Height = 256;
  wide.ParallelScale = 6.0; // the [-1, 1]^3 block covers ~1/36 of the view
  const apctest::Frame small = apctest::Render(
    grid, [](vtkAPCVolumeMapper*) {}, {}, wide);
  ASSERT_GT(small.RenderedPixels, 0);
  EXPECT_LT(small.RenderedPixels, 256 * 256 / 20) << "buffers the size of the view";
  int drawn = 0;
  for (size_t p = 0; p < small.RGBA.size() / 4; ++p)
  {
    drawn += small.RGBA[4 * p + 3] > 0 ? 1 : 0;
  }
  EXPECT_GT(drawn, 256 * 256 / 50);
  EXPECT_LE(drawn, small.RenderedPixels);
  for (int mode : { vtkAPCVolumeMapper::EXACT, vtkAPCVolumeMapper::MBOIT })
  {
    // A 64^2 view with the same pixel size and centre has exactly the wide view's pixels
    // [96, 160)^2 (pixel centres coincide): it must show the same picture there, and the
    // wide view nothing elsewhere.
    apctest::View tight = wide;
    tight.Width = tight.Height = 64;
    tight.ParallelScale = 1.5;
    const auto configure = [mode](vtkAPCVolumeMapper* m) { m->SetMode(mode); };
    const apctest::Frame a = apctest::Render(grid, configure, {}, wide);
    const apctest::Frame b = apctest::Render(grid, configure, {}, tight);
    double maxDiff = 0;
    double outside = 0;
    for (int j = 0; j < 256; ++j)
    {
      for (int i = 0; i < 256; ++i)
      {
        const bool in = i >= 96 && i < 160 && j >= 96 && j < 160;
        for (int c = 0; c < 4; ++c)
        {
          const float v = a.RGBA[4 * (static_cast<size_t>(j) * 256 + i) + c];
          if (in)
          {
            const float w = b.RGBA[4 * (static_cast<size_t>(j - 96) * 64 + (i - 96)) + c];
            maxDiff = std::max(maxDiff, static_cast<double>(std::abs(v - w)));
          }
          else
          {
            outside = std::max(outside, static_cast<double>(std::abs(v)));
          }
        }
      }
    }
    EXPECT_LT(maxDiff, 1e-5) << "mode " << mode;
    EXPECT_EQ(outside, 0.0) << "mode " << mode;
  }
}
