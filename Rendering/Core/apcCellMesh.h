// The ray marcher's own copy of a rank's cells: corner coordinates, scalars and, derived
// once per data change, every cell's face planes and scalar range.
//
// Exact ray entry and exit come from clipping the ray against the cell's face planes, which
// is exact for cells with planar faces (tetrahedra, and the usual hexahedra, wedges and
// pyramids of CFD meshes). A non-planar quad face is replaced by one plane (Newell normal
// through the face centroid). What makes the cells tile space without gaps or double counting
// is that two cells sharing a face compute that face's plane bit for bit identically: the
// plane is computed from the face's points in a canonical order (starting at the point with
// the smallest coordinates, walking towards the smaller neighbour: coordinates, not ids, which
// differ between ranks and between unmerged pieces), and only its sign differs between the two
// cells. Together with half-open sample intervals [t_in, t_out) every lattice sample of a ray
// then lands in exactly one cell, whichever rank owns it.
#ifndef apcCellMesh_h
#define apcCellMesh_h

#include "apcCellInterpolation.h"
#include "apcExactSum.h"
#include "apcUninitialized.h"

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace apc
{

// True for exactly one of n and -n (n non-zero): the first non-zero component is positive.
inline bool InPositiveHalf(const std::array<float, 3>& n)
{
  return n[0] != 0 ? n[0] > 0 : (n[1] != 0 ? n[1] > 0 : n[2] > 0);
}

struct FacePlane
{
  // Inside the cell: Normal . x - Offset <= 0 (Normal points out, unit length to float
  // rounding). The offset is the float normal's dot product with the face's centroid, in
  // double: a float offset is off by up to half an ulp of the coordinates' magnitude (0.5 at
  // 1e7), which moves faces far from the origin by more than a cell's width, while the
  // double one keeps the plane within rounding of the face wherever the mesh sits.
  std::array<float, 3> Normal;
  // 1 where the normal lies in the positive half (InPositiveHalf), else 0: of the two cells
  // sharing the face, the one that keeps a ray running inside the plane
  // (walk::CellPlanes::Clip). Stored with the plane (in what was its padding) because the
  // marcher reads it once per plane and (cell, tile): found there, its branch on the
  // normal's sign was a coin toss per plane.
  float KeepsParallelRays;
  double Offset;

  static FacePlane Make(const std::array<float, 3>& normal, double offset)
  {
    return { normal, InPositiveHalf(normal) ? 1.0f : 0.0f, offset };
  }
};

class CellMesh
{
public:
  // Points and scalars. Exactly one of PointScalars (one per point) or CellScalars (one per
  // cell) is filled. Non-finite scalars (NaN, +-inf) are allowed: their cells are transparent.
  std::vector<std::array<double, 3>> Points;
  std::vector<float> PointScalars;
  std::vector<float> CellScalars;

  // Appends a cell given its corner point ids in VTK's order for the shape (a voxel must be
  // reordered to hexahedron order by the caller). Returns the cell's index.
  int64_t AddCell(CellShape shape, const int64_t* pointIds);

  // The bulk form of AddCell, for converters that fill the cells in parallel: replaces every
  // cell by shapes (one per cell), offsets (one more, from 0: cell c's corner ids are
  // connectivity[offsets[c] .. offsets[c + 1]), as many as its shape has) and connectivity.
  void SetCells(UninitializedVector<CellShape> shapes, UninitializedVector<int64_t> offsets,
    UninitializedVector<int64_t> connectivity);
  // The same cells without a copy of their ids: offsets (one per cell and one more, from 0) and
  // connectivity (offsets[numCells] ids) are another's arrays, which owner keeps alive and
  // unchanged for as long as this mesh (or a copy of it) keeps them. A converter whose input
  // holds its cells in this very layout lends them (apcGridCells.h), instead of writing
  // memory as large as the input's cells afresh.
  struct CellsOwner
  {
    virtual ~CellsOwner() = default;
    // Whether the lent arrays are still where, and what, they were when lent (a lender whose
    // arrays may be reallocated or changed says so here; the mesh must then be made again
    // before it is used).
    virtual bool Intact() const = 0;
  };
  void SetCells(UninitializedVector<CellShape> shapes, const int64_t* offsets,
    const int64_t* connectivity, std::shared_ptr<const CellsOwner> owner);
  bool BorrowsCells() const { return this->Ids.Owner != nullptr; }
  bool CellsIntact() const { return !this->Ids.Owner || this->Ids.Owner->Intact(); }

  // Derives bounds and face planes; call after the last AddCell and before rendering.
  // Returns false, with a message, if the mesh is unusable (ids out of range, scalars missing).
  bool Finalize(std::string* error = nullptr);

  // After new values in PointScalars or CellScalars (same sizes, same cells and points): the
  // per-cell scalar ranges and the count of non-finite scalar cells, without redoing what
  // Finalize derived from the geometry (bounds, planes, shape checks). Returns false, with a
  // message, if the scalars no longer match the cells or points.
  bool RefreshScalarRanges(std::string* error = nullptr);

  int64_t GetNumberOfCells() const { return static_cast<int64_t>(this->Shapes.size()); }
  bool HasCellScalars() const { return !this->CellScalars.empty(); }
  CellShape GetShape(int64_t cell) const { return this->Shapes[cell]; }
  const int64_t* GetCellPoints(int64_t cell) const
  {
    return this->Ids.ConnectivityData + this->Ids.OffsetsData[cell];
  }
  // Brings a cell's corners towards the cache ahead of GetCorners, in two steps a few cells
  // apart: its shape and where its corner ids are (Ids), then, once those have arrived, the
  // ids and the corners' points and scalars (Corners).
  void PrefetchIds(int64_t cell) const
  {
    __builtin_prefetch(this->Shapes.data() + cell);
    __builtin_prefetch(this->Ids.OffsetsData + cell);
  }
  void PrefetchCorners(int64_t cell) const
  {
    const int64_t* ids = this->GetCellPoints(cell);
    const int n = static_cast<int>(this->Shapes[cell]);
    for (int i = 0; i < n; ++i)
    {
      __builtin_prefetch(this->Points.data() + ids[i]);
      if (!this->PointScalars.empty())
      {
        __builtin_prefetch(this->PointScalars.data() + ids[i]);
      }
    }
  }
  const FacePlane* GetPlanes(int64_t cell, int& count) const
  {
    count = this->PlaneCounts[cell];
    return this->Planes.data() + this->PlaneOffsets[cell];
  }
  // Bit p: the cell's plane p (GetPlanes) is a face on the mesh's boundary, one that no other
  // rendered cell of this mesh shares (matched by the face's corner coordinates, so pieces
  // appended without merging their points still match). Both cells of an inner face see it
  // unset, and the one cell of a boundary face set: the end weights of Sample End Weights =
  // Boundary apply at such faces only. Found by FindBoundaryPlanes, once per data change
  // (Finalize forgets them; new scalars keep them); until then every plane counts as boundary.
  uint8_t GetBoundaryPlanes(int64_t cell) const
  {
    return this->BoundaryPlanes.empty() ? uint8_t(0xFF) : this->BoundaryPlanes[cell];
  }
  // Finds the boundary planes after Finalize (nothing if found already). It costs more than
  // Finalize itself (docs/sampler.md), so it runs only where a frame asks for the planes.
  void FindBoundaryPlanes();
  bool HasBoundaryPlanes() const { return !this->BoundaryPlanes.empty() || this->Shapes.empty(); }
  // Several processes (apcBoundaryFaces.h): a face on this piece's boundary may be another
  // piece's face too, and then is inner. GetBoundaryFaces lists the faces FindBoundaryPlanes
  // left on the boundary, in cell and plane order, by their corners (FaceCorners: the same
  // numbers on every process that holds the face); ClearBoundaryFaces takes one flag per listed
  // face back (inner[i] != 0: another process holds face i) and unsets those planes' bits, after
  // which the flags are the whole mesh's (SharesBoundary). ForgetBoundaryPlanes drops them all.
  // After the boundary faces, GetBoundaryFaces also lists once each face that three or more of
  // this piece's cells hold (inner here, but another piece may hold the same face once: in one
  // process it is inner, so that piece's copy must learn of it); their flags are not read back.
  using FaceCorners = std::array<double, 12>;
  std::vector<FaceCorners> GetBoundaryFaces() const;
  void ClearBoundaryFaces(const std::vector<uint8_t>& inner);
  bool SharesBoundary() const { return this->BoundaryShared; }
  void ForgetBoundaryPlanes()
  {
    this->BoundaryPlanes.clear();
    this->CrowdedFaces.clear();
    this->BoundaryShared = false;
  }
  // xmin, xmax, ymin, ymax, zmin, zmax of one cell (from its corners: nothing reads them
  // per frame, so they are not stored) / of the whole mesh.
  std::array<double, 6> GetCellBounds(int64_t cell) const;
  const std::array<double, 6>& GetBounds() const { return this->MeshBounds; }

  // The smallest and largest corner scalar of a cell (its own value for cell scalars), NaN
  // for both if a corner scalar is not finite (NaN or +-inf), which makes every sample of the
  // cell transparent, whatever the transfer function. Computed
  // by Finalize, once per data change: with it a frame skips the cells its transfer function
  // hides (TransferTable::MayBeVisible) without interpolating them.
  const std::array<float, 2>& GetScalarRange(int64_t cell) const
  {
    return this->ScalarRanges[cell];
  }

  // Cells Finalize left out: non-finite corners, or no volume to render (collapsed or flat
  // cells: too few faces with area to enclose anything, or too thin, see apcCellShapeCheck.h).
  // They have no planes and empty bounds.
  int64_t GetNumberOfSkippedCells() const { return this->SkippedCells; }
  int64_t GetNumberOfNonFiniteCornerCells() const { return this->NonFiniteCornerCells; }
  int64_t GetNumberOfFlatCells() const { return this->FlatCells; }
  // Rendered cells with a non-finite scalar (NaN or +-inf): transparent, see GetScalarRange.
  int64_t GetNumberOfNonFiniteScalarCells() const { return this->NonFiniteScalarCells; }

  // The rendered cells' total volume, summed exactly by Finalize (the same sum whatever the
  // order of the cells or their split over processes): the default sample distance's input.
  const ExactSum& GetCellVolume() const { return this->CellVolume; }

  // Corners and scalars of one cell, ready for interpolation.
  void GetCorners(int64_t cell, CellCorners& corners) const;

private:
  // What Finalize made of a cell.
  enum class CellFate : std::uint8_t
  {
    Rendered,
    NonFiniteCorners,
    Flat
  };
  // What Finalize sums over a block of cells: their fates and the rendered ones' bounds.
  struct Summary;
  // One cell's scalar range and face planes (written to its own slots; none if left out),
  // added to summary: independent of every other cell, so cells are derived in parallel.
  CellFate DeriveCell(int64_t cell, Summary& summary);
  std::array<float, 2> ScalarRangeOf(int64_t cell) const;
  // FindBoundaryPlanes' matching: shared[slot] (a plane slot) = 1 where another face of the
  // mesh has the same corners. Index: the ids' type (32 bits where they fit).
  template <class Index>
  void MatchFaces(uint8_t* shared) const;
  // The face behind plane n of cell: its distinct corners sorted, padded with +inf.
  FaceCorners CornersOfPlane(int64_t cell, int n) const;

  // The cells' ids: this mesh's own arrays (AddCell, SetCells) or lent ones (Owner set), read
  // through the two pointers either way. A copy of a mesh points at its own copy of its own
  // arrays, or at the same lent ones.
  struct CellIds
  {
    UninitializedVector<int64_t> Offsets{ 0 };
    UninitializedVector<int64_t> Connectivity;
    std::shared_ptr<const CellsOwner> Owner;
    const int64_t* OffsetsData = nullptr;
    const int64_t* ConnectivityData = nullptr;
    int64_t ConnectivitySize = 0;

    CellIds() { this->PointAtOwn(); }
    CellIds(const CellIds& other);
    CellIds(CellIds&& other) noexcept;
    CellIds& operator=(CellIds other) noexcept;
    // After a change to the own arrays (or to none: Owner null).
    void PointAtOwn();
    // The lent ids copied into the own arrays, for AddCell after SetCells with an owner.
    void TakeOwnership(int64_t numCells);
  };

  UninitializedVector<CellShape> Shapes;
  CellIds Ids;

  // Cell c's planes are Planes[PlaneOffsets[c] ..] (a slot for every face of its shape), the
  // first PlaneCounts[c] of them used (faces without area constrain nothing; 0: left out).
  UninitializedVector<FacePlane> Planes;
  UninitializedVector<int64_t> PlaneOffsets;
  UninitializedVector<uint8_t> PlaneCounts;
  // Bit f: face f of the cell's shape has a plane (in face order, so the n-th set bit is
  // plane n); BoundaryPlanes: see GetBoundaryPlanes.
  UninitializedVector<uint8_t> PlaneFaces;
  UninitializedVector<uint8_t> BoundaryPlanes;
  // (cell, plane) of one copy of each face that three or more cells hold (GetBoundaryFaces).
  std::vector<std::pair<int64_t, int>> CrowdedFaces;
  bool BoundaryShared = false;
  UninitializedVector<std::array<float, 2>> ScalarRanges;
  std::array<double, 6> MeshBounds{ 0, -1, 0, -1, 0, -1 };
  int64_t SkippedCells = 0;
  int64_t NonFiniteCornerCells = 0;
  int64_t FlatCells = 0;
  int64_t NonFiniteScalarCells = 0;
  ExactSum CellVolume;
};

} // namespace apc

#endif
