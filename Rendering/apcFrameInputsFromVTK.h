// SPDX-License-Identifier: BSD-3-Clause
// The view state of a VTK frame in the core's terms: the renderer's camera as an
// apc::RayCamera and the volume property's transfer functions as an apc::TransferTable.
#ifndef apcFrameInputsFromVTK_h
#define apcFrameInputsFromVTK_h

#include "apcFrameAgreement.h" // for TransferSignature

#include <memory>

class vtkRenderer;
class vtkVolumeProperty;

namespace apc
{
class RayCamera;
class TransferTable;

// The rays of ren's active camera (with its window centre: a tile of a large screenshot)
// through the pixels of a width x height image covering a viewport of the given aspect
// (width / height; 0: the image's own, i.e. one ray per viewport pixel).
std::unique_ptr<RayCamera> RayCameraFromVTK(
  vtkRenderer* ren, int width, int height, double aspect = 0.0);

// The first component's colour (or gray) and opacity functions, sampled over the union of
// their ranges; opacity corrected for samples spacing apart.
std::unique_ptr<TransferTable> TransferTableFromVTK(vtkVolumeProperty* property, double spacing);

// What TransferTableFromVTK samples, in a few numbers that processes can compare: checksums
// of the colour and of the opacity table (with the unit distance), and the scalar range.
TransferSignature TransferSignatureFromVTK(vtkVolumeProperty* property);
}

#endif
