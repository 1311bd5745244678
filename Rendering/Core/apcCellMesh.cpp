#include "apcCellMesh.h"

#include "apcCellShapeCheck.h"
#include "apcParallel.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

namespace apc
{
namespace
{
// Orders points by their coordinates (x, then y, then z), ids breaking ties between
// coincident points. Coordinates, not ids, because the two cells sharing a face may number its
// points differently: cells on different ranks, or in pieces appended without merging their
// points, hold their own copies of the face's points. One pass over the coordinates (Finalize
// passes finite ones only: +0 and -0 are one value here as for == and <).
bool Precedes(const std::vector<std::array<double, 3>>& points, int64_t a, int64_t b)
{
  const std::array<double, 3>& p = points[a];
  const std::array<double, 3>& q = points[b];
  for (int d = 0; d < 3; ++d)
  {
    if (p[d] != q[d])
    {
      return p[d] < q[d];
    }
  }
  return a < b;
}

// The plane of a face computed from its points in canonical order, so that both cells
// sharing the face get the same numbers (see the header). Returns false for a face with no
// area (collapsed corners), which then constrains nothing.
bool CanonicalPlane(const std::vector<std::array<double, 3>>& points, const int64_t* ids, int size,
  std::array<float, 3>& normal, double& offset)
{
  int first = 0;
  for (int i = 1; i < size; ++i)
  {
    if (Precedes(points, ids[i], ids[first]))
    {
      first = i;
    }
  }
  // The corners' indices wrap by a subtraction, not a remainder (an integer division each).
  const int after = first + 1 == size ? 0 : first + 1;
  const int before = first == 0 ? size - 1 : first - 1;
  const int step = Precedes(points, ids[after], ids[before]) ? 1 : size - 1;
  int64_t ordered[4];
  for (int i = 0, at = first; i < size; ++i)
  {
    ordered[i] = ids[at];
    at += step;
    at -= at >= size ? size : 0;
  }
  double n[3] = { 0, 0, 0 };
  double c[3] = { 0, 0, 0 };
  for (int i = 0; i < size; ++i)
  {
    const auto& p = points[ordered[i]];
    const auto& q = points[ordered[i + 1 == size ? 0 : i + 1]];
    n[0] += (p[1] - q[1]) * (p[2] + q[2]);
    n[1] += (p[2] - q[2]) * (p[0] + q[0]);
    n[2] += (p[0] - q[0]) * (p[1] + q[1]);
    for (int d = 0; d < 3; ++d)
    {
      c[d] += p[d];
    }
  }
  const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(length > 0) || !std::isfinite(length))
  {
    return false;
  }
  // Unit normals keep t = (offset - n.o)/(n.d) well scaled whatever the cell size. The
  // normal is stored in float: the offset is taken with the rounded normal, so that the
  // stored plane passes through the centroid (to double rounding) and is only tilted by the
  // normal's rounding, an error relative to the face's size, not to its distance from the
  // origin. The rounded normal goes through float storage: kept in a double array, GCC 12
  // (-O2 and -O3) vectorised the double -> float -> double round trip of two components into
  // nothing, so the offset belonged to the unrounded normal and the stored plane missed the
  // face by the rounding times the distance from the origin (0.1 m at 1e7).
  for (int d = 0; d < 3; ++d)
  {
    normal[d] = static_cast<float>(n[d] / length);
  }
  // Over 4 corners the product by 1/4, the same number as the quotient (see DeriveCell).
  const double sum = static_cast<double>(normal[0]) * c[0] + static_cast<double>(normal[1]) * c[1] +
    static_cast<double>(normal[2]) * c[2];
  offset = size == 4 ? sum * 0.25 : sum / size;
  return true;
}
}

//------------------------------------------------------------------------------
CellMesh::CellIds::CellIds(const CellIds& other)
  : Offsets(other.Offsets)
  , Connectivity(other.Connectivity)
  , Owner(other.Owner)
  , OffsetsData(other.OffsetsData)
  , ConnectivityData(other.ConnectivityData)
  , ConnectivitySize(other.ConnectivitySize)
{
  if (!this->Owner)
  {
    this->PointAtOwn();
  }
}

CellMesh::CellIds::CellIds(CellIds&& other) noexcept
  : Offsets(std::move(other.Offsets))
  , Connectivity(std::move(other.Connectivity))
  , Owner(std::move(other.Owner))
  , OffsetsData(other.OffsetsData)
  , ConnectivityData(other.ConnectivityData)
  , ConnectivitySize(other.ConnectivitySize)
{
  if (!this->Owner)
  {
    this->PointAtOwn();
  }
  other.Owner.reset();
  other.PointAtOwn();
}

CellMesh::CellIds& CellMesh::CellIds::operator=(CellIds other) noexcept
{
  this->Offsets.swap(other.Offsets);
  this->Connectivity.swap(other.Connectivity);
  this->Owner.swap(other.Owner);
  this->OffsetsData = other.OffsetsData;
  this->ConnectivityData = other.ConnectivityData;
  this->ConnectivitySize = other.ConnectivitySize;
  if (!this->Owner)
  {
    this->PointAtOwn();
  }
  return *this;
}

void CellMesh::CellIds::PointAtOwn()
{
  this->OffsetsData = this->Offsets.data();
  this->ConnectivityData = this->Connectivity.data();
  this->ConnectivitySize = static_cast<int64_t>(this->Connectivity.size());
}

void CellMesh::CellIds::TakeOwnership(int64_t numCells)
{
  if (!this->Owner)
  {
    return;
  }
  this->Offsets.assign(this->OffsetsData, this->OffsetsData + numCells + 1);
  this->Connectivity.assign(
    this->ConnectivityData, this->ConnectivityData + this->ConnectivitySize);
  this->Owner.reset();
  this->PointAtOwn();
}

//------------------------------------------------------------------------------
int64_t CellMesh::AddCell(CellShape shape, const int64_t* pointIds)
{
  const int corners = static_cast<int>(shape);
  this->Ids.TakeOwnership(this->GetNumberOfCells());
  this->Shapes.push_back(shape);
  this->Ids.Connectivity.insert(this->Ids.Connectivity.end(), pointIds, pointIds + corners);
  this->Ids.Offsets.push_back(static_cast<int64_t>(this->Ids.Connectivity.size()));
  this->Ids.PointAtOwn();
  return static_cast<int64_t>(this->Shapes.size()) - 1;
}

//------------------------------------------------------------------------------
void CellMesh::SetCells(UninitializedVector<CellShape> shapes, UninitializedVector<int64_t> offsets,
  UninitializedVector<int64_t> connectivity)
{
  this->Shapes = std::move(shapes);
  this->Ids.Owner.reset();
  this->Ids.Offsets = std::move(offsets);
  this->Ids.Connectivity = std::move(connectivity);
  this->Ids.PointAtOwn();
}

//------------------------------------------------------------------------------
void CellMesh::SetCells(UninitializedVector<CellShape> shapes, const int64_t* offsets,
  const int64_t* connectivity, std::shared_ptr<const CellsOwner> owner)
{
  this->Shapes = std::move(shapes);
  this->Ids.Offsets = UninitializedVector<int64_t>{ 0 };
  this->Ids.Connectivity = UninitializedVector<int64_t>();
  if (!owner)
  {
    // Nothing keeps them: copied.
    const int64_t numCells = this->GetNumberOfCells();
    this->Ids.Offsets.assign(offsets, offsets + numCells + 1);
    this->Ids.Connectivity.assign(connectivity, connectivity + offsets[numCells]);
    this->Ids.Owner.reset();
    this->Ids.PointAtOwn();
    return;
  }
  this->Ids.Owner = std::move(owner);
  this->Ids.OffsetsData = offsets;
  this->Ids.ConnectivityData = connectivity;
  this->Ids.ConnectivitySize = offsets[this->GetNumberOfCells()];
}

//------------------------------------------------------------------------------
struct CellMesh::Summary
{
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  std::array<double, 6> Bounds{ kInf, -kInf, kInf, -kInf, kInf, -kInf };
  int64_t NonFiniteCorners = 0;
  int64_t Flat = 0;
  int64_t NonFiniteScalars = 0;
  ExactSum Volume; // of the rendered cells

  void Add(const Summary& other)
  {
    this->Volume.Add(other.Volume);
    for (int d = 0; d < 3; ++d)
    {
      this->Bounds[2 * d] = std::min(this->Bounds[2 * d], other.Bounds[2 * d]);
      this->Bounds[2 * d + 1] = std::max(this->Bounds[2 * d + 1], other.Bounds[2 * d + 1]);
    }
    this->NonFiniteCorners += other.NonFiniteCorners;
    this->Flat += other.Flat;
    this->NonFiniteScalars += other.NonFiniteScalars;
  }
};

//------------------------------------------------------------------------------
bool CellMesh::Finalize(std::string* error)
{
  auto fail = [error](const std::string& message)
  {
    if (error)
    {
      *error = message;
    }
    return false;
  };
  const int64_t numCells = this->GetNumberOfCells();
  const int64_t numPoints = static_cast<int64_t>(this->Points.size());
  if (!this->CellScalars.empty() && static_cast<int64_t>(this->CellScalars.size()) != numCells)
  {
    return fail("cell scalars do not match the number of cells");
  }
  if (this->CellScalars.empty() && static_cast<int64_t>(this->PointScalars.size()) != numPoints)
  {
    return fail("point scalars do not match the number of points");
  }
  for (int64_t i = 0; i < this->Ids.ConnectivitySize; ++i)
  {
    const int64_t id = this->Ids.ConnectivityData[i];
    if (id < 0 || id >= numPoints)
    {
      return fail("a cell refers to a point that does not exist");
    }
  }

  // A plane slot for every face of every cell, from the shapes alone, so that each cell
  // writes its planes in place: no per-block lists to join, and the planes' memory is written
  // once (on the wind mesh the lists and their join cost as much as the planes).
  this->PlaneOffsets.resize(static_cast<size_t>(numCells) + 1);
  this->PlaneOffsets[0] = 0;
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    this->PlaneOffsets[cell + 1] = this->PlaneOffsets[cell] + FacesOf(this->Shapes[cell]).Count;
  }
  this->Planes.resize(static_cast<size_t>(this->PlaneOffsets[numCells]));
  this->PlaneCounts.resize(numCells);
  this->PlaneFaces.resize(numCells);
  this->ScalarRanges.resize(numCells);
  // Cells are independent: fixed blocks of them derived in parallel, each block summed on
  // its own, the sums joined in block order (counts and min / max: the same whatever the
  // threads).
  constexpr int64_t kBlock = 8192;
  const int64_t blocks = (numCells + kBlock - 1) / kBlock;
  std::vector<Summary> sums(static_cast<size_t>(blocks));
  ParallelFor(0, blocks, 1,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t block = begin; block < end; ++block)
      {
        for (int64_t cell = block * kBlock; cell < std::min(numCells, (block + 1) * kBlock); ++cell)
        {
          this->DeriveCell(cell, sums[block]);
        }
      }
    });
  Summary total;
  for (const Summary& sum : sums)
  {
    total.Add(sum);
  }
  this->MeshBounds = total.Bounds;
  this->SkippedCells = total.NonFiniteCorners + total.Flat;
  this->NonFiniteCornerCells = total.NonFiniteCorners;
  this->FlatCells = total.Flat;
  this->NonFiniteScalarCells = total.NonFiniteScalars;
  this->CellVolume = total.Volume;
  if (!(this->MeshBounds[0] <= this->MeshBounds[1]))
  {
    this->MeshBounds = { 0, -1, 0, -1, 0, -1 };
  }
  this->ForgetBoundaryPlanes();
  return true;
}

//------------------------------------------------------------------------------
namespace
{
// A coordinate's bits with -0 as +0: the key under which coincident points meet (== treats
// the two zeros as one point, and so does CanonicalPlane).
uint64_t CoordinateBits(double x)
{
  const double y = x + 0.0; // -0 + 0 = +0, every other value unchanged
  uint64_t bits;
  std::memcpy(&bits, &y, sizeof bits);
  return bits;
}

// Bit for bit but for the zeros' signs (a NaN equals itself: every point finds itself).
bool SameCoordinates(const std::array<double, 3>& a, const std::array<double, 3>& b)
{
  return CoordinateBits(a[0]) == CoordinateBits(b[0]) &&
    CoordinateBits(a[1]) == CoordinateBits(b[1]) && CoordinateBits(a[2]) == CoordinateBits(b[2]);
}

uint64_t PointHash(const std::array<double, 3>& p)
{
  uint64_t h = 1469598103934665603ull;
  for (double x : p)
  {
    h = (h ^ CoordinateBits(x)) * 1099511628211ull;
    h ^= h >> 29;
  }
  return h;
}

// Every point's representative: the smallest id with the same coordinates. Faces are then
// matched by integer ids, and two faces have the same representatives exactly when their
// corners have the same coordinates: pieces appended without merging their points match as
// merged ones do. The points are bucketed by a hash of their coordinates (a counting sort,
// ids ascending within a bucket), a point's representative the first of its bucket it equals.
// Index: the matching's (32 bits where the points fit: the counting sort's arrays are memory a
// first frame touches fresh, in 4 KiB pages at their size).
template <class Index>
UninitializedVector<Index> PointRepresentatives(const std::vector<std::array<double, 3>>& points)
{
  const int64_t count = static_cast<int64_t>(points.size());
  UninitializedVector<Index> representatives(static_cast<size_t>(count));
  uint64_t buckets = 1;
  while (buckets < static_cast<uint64_t>(count))
  {
    buckets <<= 1;
  }
  // Buckets are fewer than twice the points, so a bucket's number is an Index too.
  UninitializedVector<Index> bucketOf(static_cast<size_t>(count));
  ParallelFor(0, count, 16384,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t i = begin; i < end; ++i)
      {
        bucketOf[i] = static_cast<Index>(PointHash(points[i]) & (buckets - 1));
      }
    });
  UninitializedVector<Index> starts(static_cast<size_t>(buckets) + 1);
  std::fill(starts.begin(), starts.end(), Index(0));
  for (int64_t i = 0; i < count; ++i)
  {
    ++starts[static_cast<size_t>(bucketOf[i]) + 1];
  }
  for (uint64_t b = 0; b < buckets; ++b)
  {
    starts[b + 1] += starts[b];
  }
  UninitializedVector<Index> order(static_cast<size_t>(count));
  {
    UninitializedVector<Index> next(starts.begin(), starts.end() - 1);
    for (int64_t i = 0; i < count; ++i)
    {
      order[next[bucketOf[i]]++] = static_cast<Index>(i);
    }
  }
  ParallelFor(0, static_cast<int64_t>(buckets), 16384,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t b = begin; b < end; ++b)
      {
        for (Index i = starts[b]; i < starts[b + 1]; ++i)
        {
          const std::array<double, 3>& p = points[order[i]];
          Index j = starts[b];
          while (!SameCoordinates(points[order[j]], p))
          {
            ++j;
          }
          representatives[order[i]] = order[j];
        }
      }
    });
  return representatives;
}

// A face in its bucket (the bucket is its smallest id): its other three ids and its slot, side
// by side, so that a bucket is sorted and compared in place. Ordered by ids, then slot: each
// run of equal faces in slot order, as BucketKey orders them with 32-bit ids, so that the same
// copy of a crowded face is marked whichever width the ids take.
template <class Index>
struct BucketedFace
{
  Index Ids[3];
  Index Slot;
  bool SameFace(const BucketedFace& o) const
  {
    return this->Ids[0] == o.Ids[0] && this->Ids[1] == o.Ids[1] && this->Ids[2] == o.Ids[2];
  }
  bool operator<(const BucketedFace& o) const
  {
    return this->Ids[0] != o.Ids[0] ? this->Ids[0] < o.Ids[0]
      : this->Ids[1] != o.Ids[1]    ? this->Ids[1] < o.Ids[1]
      : this->Ids[2] != o.Ids[2]    ? this->Ids[2] < o.Ids[2]
                                    : this->Slot < o.Slot;
  }
  Index SlotOf() const { return this->Slot; }
};

// With 32-bit ids a bucketed face is one 128-bit integer: its ids from the most significant
// bits down, its slot in the lowest. Sorted as integers (one compare of two words instead of
// up to three branches on ids), equal faces still meet, each run of them in slot order.
struct BucketKey
{
  unsigned __int128 Key;
  bool SameFace(const BucketKey& o) const { return (this->Key >> 32) == (o.Key >> 32); }
  bool operator<(const BucketKey& o) const { return this->Key < o.Key; }
  uint32_t SlotOf() const { return static_cast<uint32_t>(this->Key); }
};

// Fills keys with the bucket's faces as BucketKeys, sorted (true), or leaves them for
// BucketedFace's own order (false: ids of 64 bits).
template <class Index>
bool SortAsKeys(const BucketedFace<Index>*, const BucketedFace<Index>*, std::vector<BucketKey>&)
{
  return false;
}

template <>
bool SortAsKeys<uint32_t>(const BucketedFace<uint32_t>* first, const BucketedFace<uint32_t>* last,
  std::vector<BucketKey>& keys)
{
  keys.resize(static_cast<size_t>(last - first));
  for (size_t k = 0; k < keys.size(); ++k)
  {
    const BucketedFace<uint32_t>& face = first[k];
    keys[k].Key = (static_cast<unsigned __int128>(face.Ids[0]) << 96) |
      (static_cast<unsigned __int128>(face.Ids[1]) << 64) |
      (static_cast<unsigned __int128>(face.Ids[2]) << 32) | face.Slot;
  }
  std::sort(keys.begin(), keys.end());
  return true;
}

// shared[slot] for a sorted bucket (equal faces side by side): 1 where another face of the
// bucket is the same, 2 on the first copy of a face three or more cells hold (CrowdedFaces).
template <class Face>
void MarkBucket(const Face* first, const Face* last, uint8_t* shared)
{
  for (const Face* i = first; i != last; ++i)
  {
    const bool match =
      (i != first && (i - 1)->SameFace(*i)) || (i + 1 != last && (i + 1)->SameFace(*i));
    const bool crowded = (i == first || !(i - 1)->SameFace(*i)) && i + 2 < last &&
      (i + 1)->SameFace(*i) && (i + 2)->SameFace(*i);
    shared[i->SlotOf()] = crowded ? 2 : match ? 1 : 0;
  }
}
}

//------------------------------------------------------------------------------
void CellMesh::FindBoundaryPlanes()
{
  if (this->HasBoundaryPlanes())
  {
    return;
  }
  const int64_t slots = static_cast<int64_t>(this->Planes.size());
  const int64_t numPoints = static_cast<int64_t>(this->Points.size());
  UninitializedVector<uint8_t> shared(static_cast<size_t>(slots));
  if (numPoints < int64_t(UINT32_MAX) && slots < int64_t(UINT32_MAX))
  {
    this->MatchFaces<uint32_t>(shared.data());
  }
  else
  {
    this->MatchFaces<uint64_t>(shared.data());
  }
  const int64_t numCells = this->GetNumberOfCells();
  this->BoundaryPlanes.resize(numCells);
  ParallelFor(0, numCells, 8192,
    [&](int64_t begin, int64_t end)
    {
      for (int64_t cell = begin; cell < end; ++cell)
      {
        uint8_t mask = 0;
        for (int n = 0; n < this->PlaneCounts[cell]; ++n)
        {
          mask |= shared[this->PlaneOffsets[cell] + n] ? 0 : static_cast<uint8_t>(1u << n);
        }
        this->BoundaryPlanes[cell] = mask;
      }
    });
  this->CrowdedFaces.clear();
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    for (int n = 0; n < this->PlaneCounts[cell]; ++n)
    {
      if (shared[this->PlaneOffsets[cell] + n] == 2)
      {
        this->CrowdedFaces.emplace_back(cell, n);
      }
    }
  }
}

//------------------------------------------------------------------------------
CellMesh::FaceCorners CellMesh::CornersOfPlane(int64_t cell, int plane) const
{
  const int64_t* ids = this->GetCellPoints(cell);
  const CellFaces& shapeFaces = FacesOf(this->Shapes[cell]);
  FaceCorners face;
  face.fill(std::numeric_limits<double>::infinity());
  int n = 0;
  for (int f = 0; f < shapeFaces.Count; ++f)
  {
    if (!(this->PlaneFaces[cell] & (1u << f)) || n++ != plane)
    {
      continue;
    }
    // The distinct corners (-0 as +0, as the matching in the piece), sorted by coordinates,
    // padded with +inf (no corner of a rendered cell is infinite).
    std::array<std::array<double, 3>, 4> corners;
    int count = 0;
    for (int i = 0; i < shapeFaces.Size[f]; ++i)
    {
      const std::array<double, 3>& p = this->Points[ids[shapeFaces.Corner[f][i]]];
      corners[count++] = { p[0] + 0.0, p[1] + 0.0, p[2] + 0.0 };
    }
    std::sort(corners.begin(), corners.begin() + count);
    count =
      static_cast<int>(std::unique(corners.begin(), corners.begin() + count) - corners.begin());
    for (int i = 0; i < count; ++i)
    {
      std::copy(corners[i].begin(), corners[i].end(), face.begin() + 3 * i);
    }
    break;
  }
  return face;
}

//------------------------------------------------------------------------------
std::vector<CellMesh::FaceCorners> CellMesh::GetBoundaryFaces() const
{
  std::vector<FaceCorners> faces;
  const int64_t numCells = this->GetNumberOfCells();
  if (this->BoundaryPlanes.empty())
  {
    return faces;
  }
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    const uint8_t mask = this->BoundaryPlanes[cell];
    for (int n = 0; mask != 0 && n < this->PlaneCounts[cell]; ++n)
    {
      if (mask & (1u << n))
      {
        faces.push_back(this->CornersOfPlane(cell, n));
      }
    }
  }
  for (const auto& crowded : this->CrowdedFaces)
  {
    faces.push_back(this->CornersOfPlane(crowded.first, crowded.second));
  }
  return faces;
}

//------------------------------------------------------------------------------
void CellMesh::ClearBoundaryFaces(const std::vector<uint8_t>& inner)
{
  size_t next = 0;
  for (int64_t cell = 0; cell < this->GetNumberOfCells() && !this->BoundaryPlanes.empty(); ++cell)
  {
    uint8_t mask = this->BoundaryPlanes[cell];
    for (int n = 0; n < this->PlaneCounts[cell]; ++n)
    {
      if ((mask & (1u << n)) && next < inner.size() && inner[next++])
      {
        mask = static_cast<uint8_t>(mask & ~(1u << n));
      }
    }
    this->BoundaryPlanes[cell] = mask;
  }
  this->BoundaryShared = true;
}

//------------------------------------------------------------------------------
template <class Index>
void CellMesh::MatchFaces(uint8_t* shared) const
{
  // Each face with a plane as its distinct corners' representatives (PointRepresentatives),
  // bucketed by the smallest of them (a counting sort by an integer: cells near each other in
  // the mesh's order share points, so the buckets fill close together); a bucket, the faces
  // around one point, sorted by the other ids puts equal faces side by side. Sorted, not
  // compared pairwise: the wind's mixed cells put up to 126 faces around a point, 30
  // comparisons a face pairwise.
  const int64_t numCells = this->GetNumberOfCells();
  const int64_t numPoints = static_cast<int64_t>(this->Points.size());
  const UninitializedVector<Index> representatives = PointRepresentatives<Index>(this->Points);
  constexpr Index kNone = std::numeric_limits<Index>::max();
  // The faces go straight into their buckets, found in two passes over the cells (the
  // buckets' sizes, then the faces): each face's ids are formed twice, but no array of every
  // face's ids is written first (16 bytes a face slot: 32 MB on the wind, memory a first
  // frame touches fresh, which costs more than forming the faces again; docs/performance.md).
  // Pass one needs only a face's smallest representative.
  // Both passes visit the same faces: each kept one (its bit in PlaneFaces, at most
  // PlaneCounts of them: a cell left out after some planes, fewer than four, keeps their bits
  // but has no planes), with its plane's index n in the cell.
  const auto forEachKeptFace = [this](int64_t cell, auto visit)
  {
    const CellFaces& shapeFaces = FacesOf(this->Shapes[cell]);
    int n = 0;
    for (int f = 0; f < shapeFaces.Count && n < this->PlaneCounts[cell]; ++f)
    {
      if (this->PlaneFaces[cell] & (1u << f))
      {
        visit(shapeFaces, f, n++);
      }
    }
  };
  UninitializedVector<Index> starts(static_cast<size_t>(numPoints) + 1);
  std::fill(starts.begin(), starts.end(), Index(0));
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    const int64_t* ids = this->GetCellPoints(cell);
    forEachKeptFace(cell,
      [&](const CellFaces& shapeFaces, int f, int)
      {
        Index smallest = representatives[ids[shapeFaces.Corner[f][0]]];
        for (int i = 1; i < shapeFaces.Size[f]; ++i)
        {
          smallest = std::min(smallest, representatives[ids[shapeFaces.Corner[f][i]]]);
        }
        ++starts[smallest + 1];
      });
  }
  for (int64_t p = 0; p < numPoints; ++p)
  {
    starts[p + 1] += starts[p];
  }
  UninitializedVector<BucketedFace<Index>> byBucket(static_cast<size_t>(starts[numPoints]));
  {
    UninitializedVector<Index> next(starts.begin(), starts.end() - 1);
    for (int64_t cell = 0; cell < numCells; ++cell)
    {
      const int64_t* ids = this->GetCellPoints(cell);
      forEachKeptFace(cell,
        [&](const CellFaces& shapeFaces, int f, int n)
        {
          // The face's distinct representatives, ascending, padded with kNone: insertion into
          // the sorted distinct ids so far.
          Index face[4];
          int count = 0;
          for (int i = 0; i < shapeFaces.Size[f]; ++i)
          {
            const Index id = representatives[ids[shapeFaces.Corner[f][i]]];
            int at = count;
            while (at > 0 && face[at - 1] > id)
            {
              --at;
            }
            if (at > 0 && face[at - 1] == id)
            {
              continue;
            }
            for (int k = count; k > at; --k)
            {
              face[k] = face[k - 1];
            }
            face[at] = id;
            ++count;
          }
          for (int k = count; k < 4; ++k)
          {
            face[k] = kNone;
          }
          const int64_t slot = this->PlaneOffsets[cell] + n;
          byBucket[next[face[0]]++] = { { face[1], face[2], face[3] }, static_cast<Index>(slot) };
        });
    }
  }
  ParallelFor(0, numPoints, 16384,
    [&](int64_t begin, int64_t end)
    {
      std::vector<BucketKey> keys;
      for (int64_t b = begin; b < end; ++b)
      {
        BucketedFace<Index>* first = byBucket.data() + starts[b];
        BucketedFace<Index>* last = byBucket.data() + starts[b + 1];
        if (SortAsKeys<Index>(first, last, keys))
        {
          MarkBucket(keys.data(), keys.data() + keys.size(), shared);
          continue;
        }
        std::sort(first, last);
        MarkBucket(first, last, shared);
      }
    });
}

//------------------------------------------------------------------------------
CellMesh::CellFate CellMesh::DeriveCell(int64_t cell, Summary& summary)
{
  const int64_t* ids = this->GetCellPoints(cell);
  const int corners = static_cast<int>(this->Shapes[cell]);
  const double inf = std::numeric_limits<double>::infinity();
  this->ScalarRanges[cell] = this->ScalarRangeOf(cell);
  this->PlaneCounts[cell] = 0;
  this->PlaneFaces[cell] = 0;
  std::array<double, 6> b = { inf, -inf, inf, -inf, inf, -inf };
  std::array<double, 3> centroid = { 0, 0, 0 };
  bool finite = true;
  std::array<std::array<double, 3>, 8> x;
  for (int i = 0; i < corners; ++i)
  {
    const auto& p = this->Points[ids[i]];
    x[i] = p;
    for (int d = 0; d < 3; ++d)
    {
      finite = finite && std::isfinite(p[d]);
      b[2 * d] = std::min(b[2 * d], p[d]);
      b[2 * d + 1] = std::max(b[2 * d + 1], p[d]);
    }
  }
  // The mean of the corners, summed in corner order. A quotient by 4 or 8 corners is the
  // product by 1/4 or 1/8 (both are the one rounding of the same number), at a fraction of a
  // division's cost; pyramids and wedges divide.
  if ((corners & (corners - 1)) == 0)
  {
    const double inverse = 1.0 / corners;
    for (int i = 0; i < corners; ++i)
    {
      for (int d = 0; d < 3; ++d)
      {
        centroid[d] += x[i][d] * inverse;
      }
    }
  }
  else
  {
    for (int i = 0; i < corners; ++i)
    {
      for (int d = 0; d < 3; ++d)
      {
        centroid[d] += x[i][d] / corners;
      }
    }
  }
  if (!finite)
  {
    ++summary.NonFiniteCorners;
    return CellFate::NonFiniteCorners;
  }
  // The centroid and bounds just summed are MeasureCell's own (the same sums in the same
  // order): passed on, not summed again (24 divisions a hexahedron).
  const CellMeasure measure = MeasureCell(this->Shapes[cell], x, centroid, b);
  if (!(measure.RelativeThickness > kMinRelativeThickness)) // IsFlat
  {
    ++summary.Flat;
    return CellFate::Flat;
  }
  FacePlane* planes = this->Planes.data() + this->PlaneOffsets[cell];
  int count = 0;
  const CellFaces& faces = FacesOf(this->Shapes[cell]);
  for (int f = 0; f < faces.Count; ++f)
  {
    int64_t faceIds[4];
    for (int i = 0; i < faces.Size[f]; ++i)
    {
      faceIds[i] = ids[faces.Corner[f][i]];
    }
    std::array<float, 3> n;
    double offset;
    if (!CanonicalPlane(this->Points, faceIds, faces.Size[f], n, offset))
    {
      continue;
    }
    // Flipping the sign is exact, so the neighbour's copy stays bit-identical.
    const double side = static_cast<double>(n[0]) * centroid[0] +
      static_cast<double>(n[1]) * centroid[1] + static_cast<double>(n[2]) * centroid[2] - offset;
    const float sign = side > 0 ? -1.0f : 1.0f;
    planes[count++] = FacePlane::Make({ sign * n[0], sign * n[1], sign * n[2] }, sign * offset);
    this->PlaneFaces[cell] |= static_cast<uint8_t>(1u << f);
  }
  // A cell needs at least four faces with area to enclose anything; with fewer (collapsed
  // corners, a flat cell) its planes would leave rays unbounded, so it is left out.
  if (count < 4)
  {
    ++summary.Flat;
    return CellFate::Flat;
  }
  this->PlaneCounts[cell] = static_cast<uint8_t>(count);
  summary.Volume.Add(measure.Volume);
  summary.NonFiniteScalars += std::isnan(this->ScalarRanges[cell][0]) ? 1 : 0;
  for (int d = 0; d < 3; ++d)
  {
    summary.Bounds[2 * d] = std::min(summary.Bounds[2 * d], b[2 * d]);
    summary.Bounds[2 * d + 1] = std::max(summary.Bounds[2 * d + 1], b[2 * d + 1]);
  }
  return CellFate::Rendered;
}

//------------------------------------------------------------------------------
std::array<double, 6> CellMesh::GetCellBounds(int64_t cell) const
{
  const double inf = std::numeric_limits<double>::infinity();
  std::array<double, 6> b = { inf, -inf, inf, -inf, inf, -inf };
  if (this->PlaneCounts[cell] == 0)
  {
    return b; // left out: empty
  }
  const int64_t* ids = this->GetCellPoints(cell);
  for (int i = 0; i < static_cast<int>(this->Shapes[cell]); ++i)
  {
    const auto& p = this->Points[ids[i]];
    for (int d = 0; d < 3; ++d)
    {
      b[2 * d] = std::min(b[2 * d], p[d]);
      b[2 * d + 1] = std::max(b[2 * d + 1], p[d]);
    }
  }
  return b;
}

//------------------------------------------------------------------------------
bool CellMesh::RefreshScalarRanges(std::string* error)
{
  const int64_t numCells = this->GetNumberOfCells();
  const bool cellScalars = !this->CellScalars.empty();
  if ((cellScalars && static_cast<int64_t>(this->CellScalars.size()) != numCells) ||
    (!cellScalars && this->PointScalars.size() != this->Points.size()) ||
    static_cast<int64_t>(this->ScalarRanges.size()) != numCells ||
    static_cast<int64_t>(this->PlaneCounts.size()) != numCells)
  {
    if (error)
    {
      *error = "the scalars do not match the finalized mesh";
    }
    return false;
  }
  this->NonFiniteScalarCells = 0;
  for (int64_t cell = 0; cell < numCells; ++cell)
  {
    this->ScalarRanges[cell] = this->ScalarRangeOf(cell);
    // Skipped cells (no planes) are not rendered: Finalize does not count them either.
    const bool rendered = this->PlaneCounts[cell] > 0;
    this->NonFiniteScalarCells += rendered && std::isnan(this->ScalarRanges[cell][0]) ? 1 : 0;
  }
  return true;
}

//------------------------------------------------------------------------------
std::array<float, 2> CellMesh::ScalarRangeOf(int64_t cell) const
{
  // One non-finite corner (NaN or +-inf) makes the whole cell NaN, hence transparent: an
  // infinite corner would otherwise interpolate to +-inf (clamped to an end of the transfer
  // function) in some samples and to NaN (inf - inf) in others.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (this->HasCellScalars())
  {
    const float s = this->CellScalars[cell];
    return std::isfinite(s) ? std::array<float, 2>{ s, s } : std::array<float, 2>{ nan, nan };
  }
  const int64_t* ids = this->GetCellPoints(cell);
  float lo = std::numeric_limits<float>::infinity();
  float hi = -lo;
  for (int i = 0; i < static_cast<int>(this->Shapes[cell]); ++i)
  {
    const float s = this->PointScalars[ids[i]];
    if (!std::isfinite(s))
    {
      return { nan, nan };
    }
    lo = std::min(lo, s);
    hi = std::max(hi, s);
  }
  return { lo, hi };
}

//------------------------------------------------------------------------------
void CellMesh::GetCorners(int64_t cell, CellCorners& corners) const
{
  const int64_t* ids = this->GetCellPoints(cell);
  corners.Shape = this->Shapes[cell];
  const int n = static_cast<int>(corners.Shape);
  const bool cellScalars = this->HasCellScalars();
  for (int i = 0; i < n; ++i)
  {
    corners.X[i] = this->Points[ids[i]];
    corners.S[i] = cellScalars ? this->CellScalars[cell] : this->PointScalars[ids[i]];
  }
}

} // namespace apc
