// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAPCVolumeMapper
 * @brief   Ray-marching volume mapper for unstructured grids with an exact mode and the
 *          two-pass moment-based order-independent (MBOIT) mode of APC.
 *
 * Renders the cells of a vtkUnstructuredGrid (tetrahedra, pyramids, wedges, hexahedra and
 * voxels, mixed) by sampling every pixel's ray at fixed world distances from the eye,
 * t_k = k * SampleDistance: the global sample lattice, so that any split of the cells among
 * processes samples the same points exactly once. Each sample is found by exact ray/cell
 * clipping against the cell's face planes and interpolated (linear in tetrahedra, VTK's
 * trilinear / wedge / pyramid shape functions otherwise) from the point scalars, or taken
 * from the cell scalars. Opacity is corrected in absorbance form,
 * a = -ln(1 - alpha_tf) * SampleDistance / ScalarOpacityUnitDistance.
 *
 * Modes:
 * - EXACT: each pixel's samples blended front to back in depth order. The ground truth.
 * - MBOIT: pass 1 sums absorbance moments b_k = sum z^k a (z = log-warped depth), pass 2
 *   sums colour weighted by alpha * T(z), T reconstructed from the moments, and the resolve
 *   turns the sums into a colour. Both passes are order independent, which is what lets APC
 *   add them across processes (vtkAPCCompositePass) instead of sorting pieces.
 *
 * The volume is blended over what the render window already holds, and rays stop at the
 * depth already in its depth buffer, so opaque geometry and the volume mix correctly.
 * The last frame's float images (final RGBA, moments, colour sums, segment counts) are
 * available as vtkImageData for inspection and tests.
 *
 * Polyhedra and quadratic cells (and pentagonal and hexagonal prisms) are rendered through
 * the tetrahedra vtkDataSetTriangleFilter makes of them, as ParaView's Volume does. Unsupported
 * input gives an error and a blank image, never a crash: a non-unstructured input, no
 * scalars; cells of other types (lower-dimensional, higher-order Lagrange/Bezier) are named in
 * an error and skipped. Ghost cells (vtkGhostType DUPLICATECELL) and cells with no volume
 * (flat or collapsed) are skipped; non-finite scalars (NaN, +-inf) are transparent; each is
 * said once per data change.
 *
 * Threads: TBB tasks over screen tiles (NumberOfThreads; VTK's SMP backend is not touched).
 *
 * @par References:
 * X. Huang, W. Usher, et al., "Approximate Puzzlepiece Compositing", arXiv 2501.12581.
 * C. Münstermann, S. Krumpen, R. Klein, C. Peters, "Moment-Based Order-Independent
 * Transparency", Proc. ACM Comput. Graph. Interact. Tech. (I3D) 1(1), 2018.
 */

#ifndef vtkAPCVolumeMapper_h
#define vtkAPCVolumeMapper_h

#include "APCRenderingModule.h" // for export macro
#include "vtkScalarsToColors.h" // for the vector modes
#include "vtkUnstructuredGridVolumeMapper.h"

#include <memory> // for std::unique_ptr

class vtkDataArray;
class vtkImageData;
class vtkUnstructuredGridBase;
namespace apc
{
struct VolumeSettings;
}

class APCRENDERING_EXPORT vtkAPCVolumeMapper : public vtkUnstructuredGridVolumeMapper
{
public:
  static vtkAPCVolumeMapper* New();
  vtkTypeMacro(vtkAPCVolumeMapper, vtkUnstructuredGridVolumeMapper);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum ModeType
  {
    EXACT = 0,
    MBOIT = 1
  };

  enum ResolveType
  {
    /// MBOIT's resolve: total alpha 1 - exp(-b0) (exact), colour sum / weight sum.
    RENORMALISED = 0,
    /// The APC paper's plain sum of alpha_i T(z_i) c_i.
    PAPER_SUM = 1,
    /**
     * RENORMALISED with each process's own samples composited exactly (sorted per pixel)
     * and only the other processes' absorbance reconstructed from moments (global - own):
     * T(z) = T_own(z) T_others(z). One process renders the exact image (to float rounding);
     * on N processes only what crosses a piece boundary is approximated, so the image
     * depends on the partition. Costs pass 2 a per-pixel sort and, on each process, one more
     * moment image. apcHybridTransmittance.h, README.
     */
    HYBRID = 2
  };

  ///@{
  /**
   * EXACT (front-to-back blending, the reference) or MBOIT (default).
   */
  void SetMode(int mode);
  int GetMode() const;
  ///@}

  ///@{
  /**
   * Power moments in MBOIT mode: 4 (default, the paper's choice), 6 or 8. With beta 0.5, 6
   * had the best mean SSIM against the exact render in docs/evaluation.md, but its
   * transmittance query made pass 2 about 3.4 times slower on the gear teeth, it sends 16 more
   * bytes per pixel and rank, and close-up translucent shells lose (docs/evaluation.md, section 4).
   */
  void SetNumberOfMoments(int n);
  int GetNumberOfMoments() const;
  ///@}

  ///@{
  /**
   * MBOIT overestimation beta in [0,1] (default 0.3, apc::kDefaultOverestimation, as the APC
   * paper; 0.5 suits opaque slab-like data better, docs/evaluation.md).
   */
  void SetOverestimation(double beta);
  double GetOverestimation() const;
  ///@}

  ///@{
  /**
   * MBOIT moment bias epsilon in [0,1]; a negative value (default) uses the published constant
   * for the number of moments (5e-7, 5e-6, 5e-5 for 4, 6, 8).
   */
  void SetMomentBias(double bias);
  double GetMomentBias() const;
  ///@}

  ///@{
  /**
   * How MBOIT weights and turns the colour sums into a pixel: RENORMALISED (default),
   * PAPER_SUM or HYBRID (own samples exact, other processes' by moments).
   */
  void SetResolveMode(int mode);
  int GetResolveMode() const;
  ///@}

  ///@{
  /**
   * World distance between samples along a ray. 0 (default) picks 1.25 times the data's mean
   * cell size (the cube root of its cells' own volume per cell, over all processes' cells
   * under vtkAPCCompositePass), but at least 96 samples along the bounding-box diagonal; on
   * the plain lattice (Sample End Weights Off, EXACT, the HYBRID resolve) one mean cell size,
   * at least 128 samples (apcDefaultSpacing.h).
   */
  void SetSampleDistance(double distance);
  double GetSampleDistance() const;
  ///@}

  ///@{
  /**
   * Shift each pixel's sample lattice by a fraction of SampleDistance that varies from pixel
   * to pixel (interleaved gradient noise; apcLatticeJitter.h), so that the bands a fixed
   * lattice draws where thin layers meet the rays at a grazing angle become fine noise.
   * The offset depends only on the pixel: every rank still samples the same points. Off by
   * default (see the README for the measurement).
   */
  void SetLatticeJitter(bool jitter);
  bool GetLatticeJitter() const;
  vtkBooleanMacro(LatticeJitter, bool);
  ///@}

  ///@{
  /**
   * Weight the first and last sample of each cell along each ray so that the cell's samples
   * sum to the exact length of the ray inside it, and sample a cell that holds no lattice
   * point once at the middle of its piece of ray (apcEndWeights.h): a ray's sampled length no
   * longer jumps by a whole SampleDistance where a boundary face crosses a lattice point, so
   * grazing silhouettes show no lattice staircase. The weights depend only on the cell and
   * the ray: N processes still render what one renders. MBOIT (APC) mode only: the EXACT and
   * segment modes keep the plain lattice, whose sort-last runs need every sample at a lattice
   * point (docs/sampler.md), and so does the HYBRID resolve, which is the exact blend on one
   * process.
   *
   * END_WEIGHTS_BOUNDARY weights only the ends on the mesh's boundary (faces no other cell of
   * the mesh shares): the staircase is there, while at an inner face the plain lattice
   * already covers the ray exactly, so inner cells keep the plain lattice's samples and
   * cost. The boundary is the whole mesh's: on several processes, vtkAPCCompositePass matches
   * the faces between the pieces once per data change (apcBoundaryExchange.h), so N processes
   * take the samples one takes; the mapper alone sees its own input's boundary. The default:
   * the staircase goes for a few per cent of a frame's time (docs/sampler.md).
   * true / 1 is END_WEIGHTS_ALL.
   */
  enum
  {
    END_WEIGHTS_OFF = 0,
    END_WEIGHTS_ALL = 1,
    END_WEIGHTS_BOUNDARY = 2
  };
  void SetSampleEndWeights(int mode);
  int GetSampleEndWeights() const;
  vtkBooleanMacro(SampleEndWeights, int);
  ///@}

  ///@{
  /**
   * MBOIT only: stop a ray once the absorbance of its samples along it reaches ln 10^3 (a
   * transmittance of 1e-3, a quarter of an 8-bit step; chosen by measurement, docs/sampler.md),
   * leaving out samples nobody can see; a pixel's opacity changes by less than 1e-3 against
   * marching every sample. The processes agree on where each ray
   * stops, so N processes render what one process renders (docs/sampler.md). On by default:
   * leaving the hidden samples out of the moments changes MBOIT's reconstruction of the
   * visible ones, closer to the exact blend on average and at worst, though a few pixels move
   * by more than one 8-bit step against marching every sample (docs/settings.md). EXACT and
   * HYBRID march every sample.
   */
  void SetStopWhereOpaque(bool stop);
  bool GetStopWhereOpaque() const;
  vtkBooleanMacro(StopWhereOpaque, bool);
  ///@}

  ///@{
  /**
   * Memory (MiB, per process) for the first pass's samples, which the second pass re-weights
   * instead of clipping and interpolating again (8 bytes a sample; on the wind data it cut
   * the second pass from 1.2 s to 0.02 s at 512^2). The screen tiles beyond it are marched
   * again. 0 turns the cache off. Default -1: a quarter of the node's physical memory divided
   * among the processes on the node (apc::NodeShareOfMemory). Lowering it frees the memory
   * held.
   */
  void SetSampleCacheSize(int megabytes);
  int GetSampleCacheSize() const;
  ///@}

  ///@{
  /**
   * TBB threads for ray marching; 0 (default): under vtkAPCCompositePass a process takes twice
   * its share of the cores of its affinity mask (each core divided among the node's processes
   * that may run on it; cores / processes when nobody is bound), at least one, at most its
   * mask, so that ranks still rendering use the cores of ranks that wait and ranks bound to a
   * shared socket do not start a thread per core each; rendered alone, TBB decides (the
   * affinity mask).
   */
  void SetNumberOfThreads(int threads);
  int GetNumberOfThreads() const;
  ///@}

  ///@{
  /**
   * Also compute the per-pixel number of disjoint ray segments through the cells (the
   * APC paper's heatmap) into GetLastImage()'s "SegmentCount" array. Off by default.
   */
  void SetComputeSegmentCount(bool compute);
  bool GetComputeSegmentCount() const;
  vtkBooleanMacro(ComputeSegmentCount, bool);
  ///@}

  ///@{
  /**
   * What a multi-component array renders, as vtkSmartVolumeMapper's settings of the same
   * names (ParaView's "APC Volume" sets them from the colour map, as its Volume does):
   * vtkScalarsToColors::MAGNITUDE (default), COMPONENT (VectorComponent, clamped to the
   * array's components with a warning) or RGBCOLORS (not supported: the magnitude, with a
   * warning). Single-component arrays render their value whatever the mode.
   */
  void SetVectorMode(int mode);
  int GetVectorMode() const;
  void SetVectorComponent(int component);
  int GetVectorComponent() const;
  ///@}

  ///@{
  /**
   * Float images of the last frame, W x H, row 0 at the bottom, as point arrays of a
   * vtkImageData: "RGBA" (premultiplied, the volume alone), "Moments" (b0..bN, MBOIT mode),
   * "ColourSums" (sum w r, g, b, sum w; MBOIT mode), "SegmentCount" (if enabled). The image
   * also carries the field array "SampleCount" (lattice samples taken).
   */
  vtkImageData* GetLastImage();
  ///@}

  /**
   * Wall-clock seconds the last frame spent in a stage: "mesh" (copying the input, only when
   * it changed), "setup" (transfer function, camera, depth buffer, binning cells to tiles),
   * "exact", "moments" (MBOIT pass 1), "colour" (pass 2), "resolve", "segments" (counting or
   * rendering them), "blend";
   * null gives the total.
   */
  double GetLastStageSeconds(const char* stage) const;

  /**
   * The effective sample distance of the last frame.
   */
  double GetLastSampleDistance() const;

  void Render(vtkRenderer* ren, vtkVolume* vol) override;

  /**
   * The pixels the last frame rendered: the data's screen rectangle, not the whole view.
   */
  vtkIdType GetLastRenderedPixels() const;

  /**
   * All of this mapper's settings as one value, with the scalar selection of its
   * vtkAbstractMapper base: what vtkAPCCompositePass reads once per frame and hands to the
   * frame engine (apcVolumeSettings.h). Not for applications, which use the setters above.
   */
  apc::VolumeSettings GetVolumeSettings() const;

protected:
  vtkAPCVolumeMapper();
  ~vtkAPCVolumeMapper() override;

private:
  vtkAPCVolumeMapper(const vtkAPCVolumeMapper&) = delete;
  void operator=(const vtkAPCVolumeMapper&) = delete;

  // One process's frame (no composite pass). step names what runs, so that Render can say
  // what failed if it throws (its memory ran out).
  void RenderAlone(vtkRenderer* ren, vtkVolume* vol, const char*& step);

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
