// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAPCVolumeRepresentation
 * @brief   ParaView's "APC Volume" representation: distributed volume rendering of
 *          unstructured grids where every rank keeps exactly its own cells.
 *
 * Offered in the representation drop-down of unstructured grids (and of multiblock /
 * partitioned collections of them, whose leaves are appended per rank) in the standard Render
 * View. Unlike ParaView's "Volume", it never asks for ordered compositing, so the view never
 * redistributes the data into a kd-tree: each rank ray-marches its own cells with a
 * vtkAPCVolumeMapper, and a vtkAPCCompositePass, installed as the view's image processing
 * pass while an APC volume is visible, sums the moment and colour images after IceT has
 * composited the opaque geometry (Approximate Puzzlepiece Compositing).
 *
 * Uses ParaView's colour and opacity transfer functions and array selection (LookupTable,
 * ScalarOpacityFunction, ColorArrayName, ScalarOpacityUnitDistance), and exposes the APC
 * settings: SampleDistance, NumberOfMoments, Overestimation, ResolveMode and Mode (APC, a
 * local exact render of each rank's own cells, or the exact sort-last segment baseline, for
 * comparison).
 *
 * Limitations: in tile-display and CAVE modes the representation renders nothing (with a
 * warning); while another representation in the view needs ordered compositing, IceT
 * composites no depth, so opaque geometry does not occlude the APC volume.
 *
 * @par Reference:
 * X. Huang, W. Usher, et al., "Approximate Puzzlepiece Compositing", arXiv 2501.12581.
 */
#ifndef vtkAPCVolumeRepresentation_h
#define vtkAPCVolumeRepresentation_h

#include "APCParaViewModule.h" // for export macro
#include "vtkSmartPointer.h"   // for ivars
#include "vtkVolumeRepresentation.h"
#include "vtkWeakPointer.h"   // for ivars
#include "vtkWrappingHints.h" // for VTK_SIZEHINT

#include <string> // for ivars

class vtkAPCVolumeMapper;
class vtkPVRenderView;
class vtkUnstructuredGrid;
class vtkVolume;

class APCPARAVIEW_EXPORT vtkAPCVolumeRepresentation : public vtkVolumeRepresentation
{
public:
  static vtkAPCVolumeRepresentation* New();
  vtkTypeMacro(vtkAPCVolumeRepresentation, vtkVolumeRepresentation);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  int ProcessViewRequest(vtkInformationRequestKey* request_type, vtkInformation* inInfo,
    vtkInformation* outInfo) override;
  void SetVisibility(bool visible) override;

  ///@{
  /**
   * Forwarded to vtkAPCVolumeMapper.
   */
  void SetSampleDistance(double distance);
  void SetNumberOfMoments(int moments);
  void SetLatticeJitter(bool jitter);
  void SetSampleCacheSize(int megabytes);
  void SetOverestimation(double beta);
  void SetResolveMode(int mode);
  ///@}

  ///@{
  /**
   * How the ranks' volumes are combined, vtkAPCCompositePass::CompositeModeType: APC (0,
   * default); SEGMENTS (1), the exact sort-last baseline (ray segments sent to their pixel's
   * owner, sorted and blended); LOCAL_EXACT (2), each rank's own cells in exact mode, without
   * compositing (a local reference, for comparison); AUTO (3), per frame SEGMENTS or APC,
   * whichever moves fewer bytes.
   */
  void SetMode(int mode);
  vtkGetMacro(Mode, int);
  ///@}

  ///@{
  /**
   * Compositing verbosity: 1 prints every frame's stage timings and bytes on the display rank.
   */
  void SetVerbosity(int verbosity);
  vtkGetMacro(Verbosity, int);
  ///@}

  ///@{
  /**
   * Interactive frames (while the camera moves), vtkAPCCompositePass's settings: the factor on
   * the sample distance and the image reduction; 1 switches either off. Defaults 2 and 4
   * (measured: README, Performance).
   */
  void SetInteractiveSampleDistanceFactor(double factor);
  vtkGetMacro(InteractiveSampleDistanceFactor, double);
  void SetInteractiveImageReduction(int reduction);
  vtkGetMacro(InteractiveImageReduction, int);
  ///@}

  ///@{
  /**
   * vtkAPCCompositePass's MaxBandPixels in units of 2^20 pixels (default 2): a larger screen
   * rectangle is rendered and composited band by band, with one band's buffers.
   */
  void SetBandMegapixels(double megapixels);
  vtkGetMacro(BandMegapixels, double);
  ///@}

  /**
   * Does nothing: the panel's "Refresh Timings" button calls it, and the panel then pulls the
   * information properties (GetLastTimings) from the display rank.
   */
  void RefreshTimings() {}

  ///@{
  /**
   * A file (.exr or .vti) the display rank writes each frame's float image to; empty (the
   * default) writes nothing.
   */
  void SetImageFileName(const char* name);
  ///@}

  /**
   * The last frame's stage timings on this rank, in seconds: agree, depth, pass1, allreduce,
   * pass2, reduce, resolve, blend, total; then the bytes this rank sent, the composited
   * pixels, the mode that ran (vtkAPCCompositePass::GetLastCompositeMode: what Auto chose),
   * the covered pixels, the seconds of the "tiles" stage and the image reduction the frame
   * ran with (1 still, InteractiveImageReduction interactive, 0 skipped): 15 values.
   */
  double* GetLastTimings() VTK_SIZEHINT(15);
  /**
   * The last SEGMENTS frame on this rank: seconds of segments, exchange, blend_segments and
   * gather; messages sent; average and maximum segments per non-empty pixel (all ranks).
   */
  double* GetLastSegmentStatistics() VTK_SIZEHINT(7);

  vtkAPCVolumeMapper* GetMapper();

protected:
  vtkAPCVolumeRepresentation();
  ~vtkAPCVolumeRepresentation() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  bool AddToView(vtkView* view) override;
  bool RemoveFromView(vtkView* view) override;

  void UpdateMapperArray();
  void Attach(bool attach);

  vtkSmartPointer<vtkAPCVolumeMapper> Mapper;
  vtkSmartPointer<vtkUnstructuredGrid> LocalPiece;
  vtkSmartPointer<vtkVolume> APCVolume; // what the pass renders; never a prop of the renderer
  vtkWeakPointer<vtkPVRenderView> View;
  int Mode = 0;
  int Verbosity = 0;
  std::string ImageFileName;
  double InteractiveSampleDistanceFactor = 2.0;
  int InteractiveImageReduction = 4;
  double BandMegapixels = 2.0;
  double LastTimings[15] = {};
  double LastSegmentStatistics[7] = {};

private:
  vtkAPCVolumeRepresentation(const vtkAPCVolumeRepresentation&) = delete;
  void operator=(const vtkAPCVolumeRepresentation&) = delete;
};

#endif
