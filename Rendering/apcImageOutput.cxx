// SPDX-License-Identifier: BSD-3-Clause
#include "apcImageOutput.h"

#include "vtkAPCEXRWriter.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderUtilities.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkPointData.h"
#include "vtkRenderer.h"
#include "vtkShaderProgram.h"
#include "vtkSmartPointer.h"
#include "vtkTextureObject.h"
#include "vtkXMLImageDataWriter.h"
#include "vtk_glew.h"

#include <algorithm>
#include <string>
#include <type_traits>
#include <vector>

namespace apc
{

namespace
{
// Blends one float texture over the viewport at (x0, y0).
void BlendTexture(vtkOpenGLRenderWindow* window, int x0, int y0, int width, int height,
  int imageWidth, int imageHeight, const float* rgba)
{
  vtkNew<vtkTextureObject> texture;
  texture->SetContext(window);
  texture->Create2DFromRaw(imageWidth, imageHeight, 4, VTK_FLOAT,
    const_cast<float*>(rgba)); // only read, despite the signature
  // One texel per pixel stays exact (nearest); a reduced image is interpolated, which is
  // right for premultiplied colours.
  const bool stretched = imageWidth != width || imageHeight != height;
  texture->SetMinificationFilter(stretched ? vtkTextureObject::Linear : vtkTextureObject::Nearest);
  texture->SetMagnificationFilter(stretched ? vtkTextureObject::Linear : vtkTextureObject::Nearest);
  std::string fragment = vtkOpenGLRenderUtilities::GetFullScreenQuadFragmentShaderTemplate();
  vtkShaderProgram::Substitute(fragment, "//VTK::FSQ::Decl", "uniform sampler2D volumeImage;");
  vtkShaderProgram::Substitute(
    fragment, "//VTK::FSQ::Impl", "gl_FragData[0] = texture2D(volumeImage, texCoord);");
  {
    vtkOpenGLQuadHelper quad(window,
      vtkOpenGLRenderUtilities::GetFullScreenQuadVertexShader().c_str(), fragment.c_str(), "");
    window->GetShaderCache()->ReadyShaderProgram(quad.Program);
    texture->Activate();
    quad.Program->SetUniformi("volumeImage", texture->GetTextureUnit());
    vtkOpenGLState* state = window->GetState();
    vtkOpenGLState::ScopedglEnableDisable blend(state, GL_BLEND);
    vtkOpenGLState::ScopedglEnableDisable depthTest(state, GL_DEPTH_TEST);
    vtkOpenGLState::ScopedglBlendFuncSeparate blendFunction(state);
    vtkOpenGLState::ScopedglDepthMask depthMask(state);
    vtkOpenGLState::ScopedglViewport viewport(state);
    vtkOpenGLState::ScopedglEnableDisable scissor(state, GL_SCISSOR_TEST);
    state->vtkglEnable(GL_BLEND);
    state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    state->vtkglDisable(GL_DEPTH_TEST);
    state->vtkglDisable(GL_SCISSOR_TEST);
    state->vtkglDepthMask(GL_FALSE);
    state->vtkglViewport(x0, y0, width, height);
    quad.Render();
    texture->Deactivate();
    quad.ReleaseGraphicsResources(window);
  }
  texture->ReleaseGraphicsResources(window);
}

// An image at one texel per pixel is blended in bands of rows of at most this many pixels:
// a software OpenGL keeps a texture's copy in memory, 16 bytes per pixel of the whole
// image otherwise (1 GB at 8192^2).
constexpr int kBlendBandPixels = 1 << 20;
}

void BlendIntoWindow(vtkRenderer* ren, int x0, int y0, int width, int height, int imageWidth,
  int imageHeight, const float* rgba)
{
  // A float texture on a viewport quad, blended premultiplied-over into whatever framebuffer
  // is bound: the window's in plain VTK, the one IceT composited into in ParaView (its
  // result is captured from there, so drawing anywhere else would be lost). Float keeps
  // the 8-bit quantisation of glDrawPixels out of the volume's colours.
  auto* window = vtkOpenGLRenderWindow::SafeDownCast(ren->GetRenderWindow());
  if (!window || width < 1 || height < 1 || imageWidth < 1 || imageHeight < 1)
  {
    return;
  }
  if (imageWidth != width || imageHeight != height)
  {
    // A reduced image is interpolated as a whole (it is small: 1/r^2 of the viewport).
    BlendTexture(window, x0, y0, width, height, imageWidth, imageHeight, rgba);
    return;
  }
  const int rows = std::max(1, kBlendBandPixels / width);
  for (int j = 0; j < height; j += rows)
  {
    const int n = std::min(rows, height - j);
    BlendTexture(window, x0, y0 + j, width, n, width, n, rgba + 4 * static_cast<size_t>(width) * j);
  }
}

void StoreFloatImages(
  vtkImageData* image, int width, int height, const ScreenRect& rect, const FloatImages& images)
{
  // The previous frame's arrays are refilled when their size fits, not allocated again: at
  // 1024^2 new arrays cost ~0.1 s a frame in page faults.
  vtkPointData* previous = image->GetPointData();
  std::vector<vtkSmartPointer<vtkDataArray>> kept;
  const vtkIdType pixels = static_cast<vtkIdType>(width) * height;
  auto add = [&](auto* prototype, const char* name, int components, const auto* values)
  {
    if (!values)
    {
      return;
    }
    using Array = std::remove_pointer_t<decltype(prototype)>;
    vtkSmartPointer<Array> array = Array::SafeDownCast(previous->GetAbstractArray(name));
    if (!array)
    {
      array = vtkSmartPointer<Array>::New();
      array->SetName(name);
    }
    array->SetNumberOfComponents(components);
    array->SetNumberOfTuples(pixels);
    auto* full = array->GetPointer(0);
    std::fill(full, full + components * pixels, 0);
    if (rect.Pixels() > 0)
    {
      Unpack(values, width, rect, components, full);
    }
    kept.emplace_back(array);
  };
  add(static_cast<vtkFloatArray*>(nullptr), "RGBA", 4, images.RGBA);
  add(static_cast<vtkFloatArray*>(nullptr), "Moments", images.MomentComponents, images.Moments);
  add(static_cast<vtkFloatArray*>(nullptr), "ColourSums", 4, images.ColourSums);
  add(static_cast<vtkIntArray*>(nullptr), "SegmentCount", 1, images.SegmentCount);
  image->Initialize();
  image->SetDimensions(width, height, 1);
  for (const auto& array : kept)
  {
    image->GetPointData()->AddArray(array);
  }
  vtkNew<vtkDoubleArray> sampleCount;
  sampleCount->SetName("SampleCount");
  sampleCount->InsertNextValue(static_cast<double>(images.SampleCount));
  image->GetFieldData()->AddArray(sampleCount);
}

//------------------------------------------------------------------------------
void WriteFloatImages(vtkImageData* image, const char* fileName)
{
  const std::string name = fileName;
  if (name.size() > 4 && name.compare(name.size() - 4, 4, ".exr") == 0)
  {
    vtkNew<vtkAPCEXRWriter> writer;
    writer->SetFileName(name.c_str());
    writer->SetInputData(image);
    writer->Write();
  }
  else
  {
    vtkNew<vtkXMLImageDataWriter> writer;
    writer->SetFileName(name.c_str());
    writer->SetInputData(image);
    writer->SetDataModeToBinary(); // Debian's ParaView rejects appended-mode XML
    writer->Write();
  }
}

} // namespace apc
