// Whether a cell is too flat to render: the check CellMesh::Finalize runs once per data change.
//
// The ray marcher bounds a cell by its face planes, each oriented away from the cell's
// centroid. In a cell with (almost) no volume, four distinct coplanar tetrahedron corners
// say, every face plane is the same plane and the centroid lies on it, so the orientations
// come out arbitrary and the "cell" becomes a half-space or an unbounded slab: an opaque
// block on screen. Such cells hold no volume to render, so they are left out.
//
// The criterion is scale-free: the cell's thickness relative to its size,
//   RelativeThickness = |V| / (A_max * D),
// with V the cell's volume (divergence theorem over its faces, triangulated from their first
// corner, around the centroid), A_max its largest face area and D the diagonal of its
// bounding box. A slab of size L x L x h gives about h / (1.4 L), a needle L x h x h about
// h / L (volume over the longest edge cubed would call a 1000:1 needle flat), a cube
// 1 / sqrt 3 = 0.58, the corner tetrahedron of a cube 1/9. Translating or scaling a cell does
// not change it (to rounding).
//
// The threshold: planes are stored in float, whose unit normals carry errors of about 6e-8.
// A cell thinner than about a hundred times that can no longer be trusted to be bounded by its
// rounded planes, and it holds a negligible share of any ray (its thickness in units of its
// size), so kMinRelativeThickness = 1e-6.
//
// FacesOf gives each shape's faces from the one cell facet table (Filters/Core/apcCellFacets),
// which CellMesh takes its planes from too.
#ifndef apcCellShapeCheck_h
#define apcCellShapeCheck_h

#include "apcCellFacets.h"
#include "apcCellInterpolation.h"

#include <array>

namespace apc
{

constexpr double kMinRelativeThickness = 1e-6;

// The faces of a shape in VTK's corner numbering, as VTK lists them: consistently oriented
// (all outward, or all inward for the wedge, whose corner order VTK flips), which the volume
// needs; CellMesh orients its planes by the centroid instead.
using CellFaces = CellFacets;
const CellFaces& FacesOf(CellShape shape);

// A cell's volume |V| (as above: the divergence theorem over its triangulated faces) and its
// RelativeThickness, from one pass over its faces (CellMesh::Finalize needs both).
struct CellMeasure
{
  double Volume = 0;
  double RelativeThickness = 0;
};
CellMeasure MeasureCell(CellShape shape, const std::array<std::array<double, 3>, 8>& corners);
// The same, given the corners' centroid (the sum of corner / corners, in corner order) and
// bounds (xmin, xmax, ymin, ymax, zmin, zmax), which CellMesh::Finalize has computed already:
// with exactly these inputs the result is the one above, bit for bit.
CellMeasure MeasureCell(CellShape shape, const std::array<std::array<double, 3>, 8>& corners,
  const std::array<double, 3>& centroid, const std::array<double, 6>& bounds);

// |V| / (A_max * D) as above for the corners of a cell (VTK's corner order for its shape); 0
// for a cell with no face area or no extent; NaN or 0 if a corner is not finite.
double RelativeThickness(CellShape shape, const std::array<std::array<double, 3>, 8>& corners);

// True if the cell has no volume to render (RelativeThickness not above the threshold; NaN
// corners count as flat too).
inline bool IsFlat(CellShape shape, const std::array<std::array<double, 3>, 8>& corners)
{
  return !(RelativeThickness(shape, corners) > kMinRelativeThickness);
}

} // namespace apc

#endif
