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

#include <memory> // for std::unique_ptr
#include <string> // for ivars

class vtkAPCVolumeMapper;
class vtkPVRenderView;
class vtkUnstructuredGrid;
class vtkVolume;
namespace apc
{
struct ViewRequest;
}

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
  void SetSampleEndWeights(int mode);
  void SetStopWhereOpaque(bool stop);
  void SetSampleCacheSize(int megabytes);
  void SetOverestimation(double beta);
  void SetResolveMode(int mode);
  ///@}

  /**
   * The settings below are the view's (its vtkAPCCompositePass's), not this volume's: every
   * APC volume of a view asks for them, the view follows the one shown first, and a volume
   * asking for something else is told so, once (apcPassInstaller.h).
   */

  ///@{
  /**
   * How the ranks' volumes are combined, vtkAPCCompositePass::CompositeModeType: APC (0,
   * default); SEGMENTS (1), the exact sort-last baseline (ray segments sent to their pixel's
   * owner, sorted and blended); LOCAL_EXACT (2), each rank's own cells in exact mode, without
   * compositing (a local reference, for comparison); AUTO (3), per frame SEGMENTS or APC,
   * whichever moves fewer bytes.
   */
  void SetMode(int mode);
  int GetMode() const;
  ///@}

  ///@{
  /**
   * Compositing verbosity: 1 prints every frame's stage timings and bytes on the display rank.
   */
  void SetVerbosity(int verbosity);
  int GetVerbosity() const;
  ///@}

  ///@{
  /**
   * Interactive frames (while the camera moves), vtkAPCCompositePass's settings: the factor on
   * the sample distance and the image reduction; 1 switches either off.
   */
  void SetInteractiveSampleDistanceFactor(double factor);
  double GetInteractiveSampleDistanceFactor() const;
  void SetInteractiveImageReduction(int reduction);
  int GetInteractiveImageReduction() const;
  ///@}

  ///@{
  /**
   * vtkAPCCompositePass's MaxBandPixels in units of 2^20 pixels: a larger screen rectangle is
   * rendered and composited band by band, with one band's buffers.
   */
  void SetBandMegapixels(double megapixels);
  double GetBandMegapixels() const;
  ///@}

  /**
   * Nothing to do here (every frame keeps its timings): the panel's "Refresh Timings" button
   * pushes it, and vtkSMAPCVolumeRepresentationProxy then pulls GetLastTimings from the
   * display rank, which fills "Last Timings".
   */
  void RefreshTimings() {}

  ///@{
  /**
   * A file (.exr or .vti) the display rank writes each frame's float image to; empty (the
   * default) writes nothing.
   */
  void SetImageFileName(const char* name);
  const char* GetImageFileName() const;
  ///@}

  /**
   * The last frame on this rank, vtkAPCCompositePass::Timings' fields in their order (all zero
   * but mode -1 before a frame): what the "APCLastTimings" information property holds. Read
   * them by name, with GetLastTimingNames (apcparaview.last_timings in Python), never by
   * position: fields are added as the pass measures more.
   */
  double* GetLastTimings() VTK_SIZEHINT(74);
  /**
   * The names of GetLastTimings' values, in their order, separated by spaces.
   */
  const char* GetLastTimingNames();
  /**
   * The last frame's render seconds of every rank, in rank order, separated by spaces (on the
   * display rank; elsewhere the rank's own): vtkAPCCompositePass::GetLastRankRenderSeconds.
   */
  const char* GetLastRankRenderSeconds();

  vtkAPCVolumeMapper* GetMapper();

protected:
  vtkAPCVolumeRepresentation();
  ~vtkAPCVolumeRepresentation() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  bool AddToView(vtkView* view) override;
  bool RemoveFromView(vtkView* view) override;

  // Hands the chosen array to the mapper; false if there is none (Solid Color).
  bool UpdateMapperArray();
  void Attach(bool attach);

  vtkSmartPointer<vtkAPCVolumeMapper> Mapper;
  vtkSmartPointer<vtkUnstructuredGrid> LocalPiece;
  vtkWeakPointer<vtkDataObject> PieceSource; // the input LocalPiece was made of, and when
  vtkMTimeType PieceSourceTime = 0;
  vtkSmartPointer<vtkVolume> APCVolume; // what the pass renders; never a prop of the renderer
  vtkWeakPointer<vtkPVRenderView> View;
  std::unique_ptr<apc::ViewRequest> ViewRequest; // the view settings above, for the pass
  bool SaidNoArray = false; // that Solid Color draws nothing, until an array is chosen
  double LastTimings[74] = {};
  std::string LastTimingNames;
  std::string LastRankRenderSeconds;

private:
  vtkAPCVolumeRepresentation(const vtkAPCVolumeRepresentation&) = delete;
  void operator=(const vtkAPCVolumeRepresentation&) = delete;
};

#endif
