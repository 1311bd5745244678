// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkAPCEXRWriter
 * @brief   Writes the float point arrays of a 2D vtkImageData as one OpenEXR file.
 *
 * For the float images APC produces (vtkAPCVolumeMapper::GetLastImage(): the premultiplied
 * RGBA, the moments, the colour sums; the per-rank partial images of the distributed pass),
 * which 8-bit PNGs would clip and quantise. Every point array becomes channels named
 * "<array>.<component>", except a 4-component "RGBA" array, which becomes the standard
 * R, G, B, A channels that image viewers show. Channels are 32-bit float; rows are flipped
 * so that the top of the picture is the top of the file, as viewers expect.
 *
 * Errors (no input, not 2D, no arrays, an unwritable file) are reported with vtkErrorMacro
 * and leave no partial file behind where OpenEXR allows.
 */
#ifndef vtkAPCEXRWriter_h
#define vtkAPCEXRWriter_h

#include "APCRenderingModule.h" // for export macro
#include "vtkWriter.h"

class vtkImageData;

class APCRENDERING_EXPORT vtkAPCEXRWriter : public vtkWriter
{
public:
  static vtkAPCEXRWriter* New();
  vtkTypeMacro(vtkAPCEXRWriter, vtkWriter);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /**
   * The file to write.
   */
  vtkSetFilePathMacro(FileName);
  vtkGetFilePathMacro(FileName);
  ///@}

protected:
  vtkAPCEXRWriter() = default;
  ~vtkAPCEXRWriter() override;

  void WriteData() override;
  int FillInputPortInformation(int port, vtkInformation* info) override;

  char* FileName = nullptr;

private:
  vtkAPCEXRWriter(const vtkAPCEXRWriter&) = delete;
  void operator=(const vtkAPCEXRWriter&) = delete;
};

#endif
