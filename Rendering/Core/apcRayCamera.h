// Primary rays of a pinhole (perspective) or parallel camera, one through each pixel centre,
// with the same conventions as VTK's camera (vertical view angle, image row 0 at the bottom,
// window centre), so that images and depth buffers line up with what VTK draws.
//
// The window centre shifts the image plane as vtkCamera's does (in units of half the view
// height/width): a tile of a large screenshot is rendered by a camera whose view angle is
// narrowed and whose window centre is moved onto the tile, so the tile's rays are exactly the
// full image's rays through those pixels. The aspect is the viewport's: an image rendered at
// reduced resolution covers the same frustum with fewer, larger pixels.
//
// A cropped camera (Cropped) is a rectangle of another's pixels: its pixel (i, j) has the same
// ray as the full camera's pixel (i + I0, j + J0). Rendering only the pixels whose rays can
// meet the data keeps every per-pixel buffer the size of the data's footprint on screen, not
// of the view (8192^2 views on a few ranks).
//
// t is the world-space distance along a ray from its origin: the eye for a perspective camera,
// the plane through the eye perpendicular to the view direction for a parallel one. The
// ray marcher samples at t_k = k * spacing, the global sample lattice that every rank shares.
#ifndef apcRayCamera_h
#define apcRayCamera_h

#include <array>

namespace apc
{

struct Ray
{
  std::array<double, 3> Origin;
  std::array<double, 3> Direction; // unit length
};

class RayCamera
{
public:
  // viewAngle: full vertical angle in degrees (perspective). parallelScale: half the view
  // height in world units (parallel). near/far: the clipping range, for depth conversion.
  // windowCenter: vtkCamera's WindowCenter. aspect: width / height of the frustum; 0 uses
  // width / height of the image.
  RayCamera(const std::array<double, 3>& position, const std::array<double, 3>& focalPoint,
    const std::array<double, 3>& viewUp, double viewAngle, bool parallel, double parallelScale,
    int width, int height, double nearClip, double farClip,
    const std::array<double, 2>& windowCenter = { 0.0, 0.0 }, double aspect = 0.0);

  // The camera of the pixels [i0, i0 + width) x [j0, j0 + height) of this one (clamped to
  // at least one pixel): same frustum, same rays, pixel indices relative to (i0, j0). Of an
  // undecimated camera only (Decimated comes after the crop).
  RayCamera Cropped(int i0, int j0, int width, int height) const;

  // The camera of every step-th pixel of this one in each direction: its pixel (i, j) has the
  // same ray as this camera's pixel (i * step + offset, j * step + offset), and it has as many
  // pixels as that leaves inside this one. A coarse set of the very rays this camera casts
  // (the opaque stop's first-frame probe, apcOpaquePrediction.h). step >= 1, 0 <= offset < step.
  RayCamera Decimated(int step, int offset) const;

  // The pixels this camera renders (the crop's size; the full image if not cropped).
  int GetWidth() const { return this->Width; }
  int GetHeight() const { return this->Height; }
  // Where pixel (0, 0) lies in the uncropped image: global pixel (i + I0, j + J0) is what
  // must not depend on the crop (the lattice jitter's pattern, for one).
  int GetCropI0() const { return this->CropI0; }
  int GetCropJ0() const { return this->CropJ0; }
  // The uncropped, undecimated image's column and row of pixel (i, j).
  int ImageColumn(int i) const { return i * this->Step + this->Offset + this->CropI0; }
  int ImageRow(int j) const { return j * this->Step + this->Offset + this->CropJ0; }
  bool IsParallel() const { return this->Parallel; }
  const std::array<double, 3>& GetPosition() const { return this->Position; }
  const std::array<double, 3>& GetViewDirection() const { return this->Forward; }

  // The ray through the centre of pixel (i, j).
  Ray PixelRay(int i, int j) const;

  // Continuous pixel coordinates of a world point (pixel centres at integers). False when
  // the point is not in front of the eye, where a perspective projection is meaningless.
  bool Project(const std::array<double, 3>& x, double& px, double& py) const;

  // Distance along pixel (i, j)'s ray to the surface whose OpenGL depth-buffer value (in
  // [0,1]) is depth; +inf for the cleared value 1.
  double DistanceFromDepth(int i, int j, double depth) const;

  // Smallest and largest t at which a ray may meet the box (xmin,xmax,ymin,ymax,zmin,zmax):
  // the range the depth warp must cover, the same on every rank given the same box.
  void DistanceRange(const std::array<double, 6>& bounds, double& tmin, double& tmax) const;

private:
  std::array<double, 3> Position;
  std::array<double, 3> Forward;
  std::array<double, 3> Right;
  std::array<double, 3> Up;
  bool Parallel;
  double HalfHeight; // tan(angle/2) for perspective, parallel scale for parallel
  double Aspect;
  std::array<double, 2> Center; // vtkCamera's WindowCenter
  int Width;
  int Height;
  int FullWidth; // the uncropped image: the pixel size in the image plane
  int FullHeight;
  int CropI0 = 0;
  int CropJ0 = 0;
  int Step = 1; // Decimated: pixel i is the undecimated crop's pixel i * Step + Offset
  int Offset = 0;
  double Near;
  double Far;
};

} // namespace apc

#endif
