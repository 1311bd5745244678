// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAPCCompositePass
 * @brief   Approximate Puzzlepiece Compositing: distributed volume rendering of
 *          unstructured pieces that stay on their process, by summing moment images.
 *
 * Replaces sort-last compositing for the volumes added with AddVolume() (whose mappers must
 * be vtkAPCVolumeMapper; the volumes must NOT also be props of the renderer). Every process
 * runs Render() in lockstep; per frame it does, whatever the partition:
 *
 * 1. the delegate pass, if any (the opaque scene; in ParaView, IceT's composited result);
 * 2. one small allreduce: the union of all processes' data bounds (depth warp, sample
 *    spacing, screen rectangle) and a failure flag, so that a process whose input is
 *    unusable makes every process skip the frame instead of waiting in a collective;
 * 3. a broadcast of the display process's depth over the data's screen rectangle, so that
 *    every process stops its rays at the composited opaque geometry;
 * 4. pass 1 on the local cells: the moment image; one allreduce (sum) of it;
 * 5. pass 2 with the global moments: the colour-sum image; one reduce (sum) to the display
 *    process;
 * 6. on the display process: resolve, and blend over the opaque image in the render window.
 *
 * Only the screen rectangle the data's bounds cover is sent. Moment and colour sums travel
 * in double precision (CompositeInDouble, default on) so that the distributed image equals
 * the one-process MBOIT image to rounding; off halves the bytes.
 *
 * Volumes share one moment image, so several APC volumes are composited order-independently
 * together; they must then use the same NumberOfMoments, and the first volume's
 * Overestimation, MomentBias and ResolveMode apply to all.
 *
 * Works with any vtkMultiProcessController (vtkMPIController for real runs; none or a
 * single process renders locally). In ParaView it is installed as the view's image
 * processing pass, after IceT.
 *
 * @par Reference:
 * X. Huang, W. Usher, et al., "Approximate Puzzlepiece Compositing", arXiv 2501.12581.
 */
#ifndef vtkAPCCompositePass_h
#define vtkAPCCompositePass_h

#include "APCRenderingModule.h" // for export macro
#include "vtkImageProcessingPass.h"

#include <memory> // for std::unique_ptr

class vtkImageData;
class vtkMultiProcessController;
class vtkVolume;

class APCRENDERING_EXPORT vtkAPCCompositePass : public vtkImageProcessingPass
{
public:
  static vtkAPCCompositePass* New();
  vtkTypeMacro(vtkAPCCompositePass, vtkImageProcessingPass);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void Render(const vtkRenderState* s) override;
  void ReleaseGraphicsResources(vtkWindow* w) override;

  ///@{
  /**
   * The processes that render together. Default: the global controller at construction.
   */
  void SetController(vtkMultiProcessController* controller);
  vtkGetObjectMacro(Controller, vtkMultiProcessController);
  ///@}

  ///@{
  /**
   * The volumes this pass renders (vtkAPCVolumeMapper volumes, not props of the renderer).
   */
  void AddVolume(vtkVolume* volume);
  void RemoveVolume(vtkVolume* volume);
  void RemoveAllVolumes();
  int GetNumberOfVolumes() const;
  ///@}

  ///@{
  /**
   * The process that shows the image (IceT's root). Default 0.
   */
  vtkSetClampMacro(DisplayProcess, int, 0, VTK_INT_MAX);
  vtkGetMacro(DisplayProcess, int);
  ///@}

  ///@{
  /**
   * Sum moments and colours in double (default) or float precision.
   */
  vtkSetMacro(CompositeInDouble, bool);
  vtkGetMacro(CompositeInDouble, bool);
  vtkBooleanMacro(CompositeInDouble, bool);
  ///@}

  ///@{
  /**
   * Use the volumes' EXACT mode instead of APC, without compositing: each process blends
   * only its own cells (a local reference; in parallel the display process shows its own
   * piece only). Default off.
   */
  vtkSetMacro(LocalExact, bool);
  vtkGetMacro(LocalExact, bool);
  vtkBooleanMacro(LocalExact, bool);
  ///@}

  ///@{
  /**
   * 0: silent; 1: the display process prints the stage timings and bytes of every frame.
   */
  vtkSetClampMacro(Verbosity, int, 0, 2);
  vtkGetMacro(Verbosity, int);
  ///@}

  ///@{
  /**
   * The last frame, per process: wall-clock seconds of a stage ("agree", "depth", "pass1",
   * "allreduce", "pass2", "reduce", "resolve", "blend"; null for the total), bytes this
   * process sent into the collectives, and the screen pixels composited.
   */
  double GetLastStageSeconds(const char* stage) const;
  double GetLastBytesSent() const;
  vtkIdType GetLastCompositedPixels() const;
  ///@}

  ///@{
  /**
   * If set, the display process writes every frame's final float image (premultiplied RGBA
   * of the volumes and the global moments) to this file: OpenEXR for ".exr", VTK XML image
   * data (binary, readable everywhere) for ".vti".
   */
  vtkSetFilePathMacro(ImageFileName);
  vtkGetFilePathMacro(ImageFileName);
  ///@}

  /**
   * Whether the last frame was skipped because a process could not render (message on the
   * display process).
   */
  bool GetLastFrameFailed() const;

  /**
   * The last final float image on the display process (premultiplied RGBA of the volumes,
   * before blending) and the global moments, as point arrays "RGBA" and "Moments".
   */
  vtkImageData* GetLastImage();

protected:
  vtkAPCCompositePass();
  ~vtkAPCCompositePass() override;

  vtkMultiProcessController* Controller = nullptr;
  int DisplayProcess = 0;
  bool CompositeInDouble = true;
  bool LocalExact = false;
  int Verbosity = 0;
  char* ImageFileName = nullptr;

private:
  vtkAPCCompositePass(const vtkAPCCompositePass&) = delete;
  void operator=(const vtkAPCCompositePass&) = delete;

  void WriteImage();

  struct Internals;
  std::unique_ptr<Internals> Internal;
};

#endif
