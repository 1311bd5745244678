// The float images of a frame survive a round trip through OpenEXR (read back with OpenEXR's
// own reader, not ours): channel names, values bit for bit (float32), orientation.

#include "apcTestGrids.h"
#include "apcTestImages.h"
#include "apcTestRender.h"

#include "vtkAPCEXRWriter.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>

#include <gtest/gtest.h>

namespace
{
TEST(EXRWriter, MapperImagesRoundTrip)
{
  auto grid = apctest::HexBlock(4, [](double x, double, double z) { return 0.5 + 0.4 * x * z; });
  apctest::View view;
  view.Width = 40;
  view.Height = 24; // not square, so a transposed or flipped read shows
  view.Parallel = false;
  view.Position = { 1.0, 2.0, 4.0 };
  vtkSmartPointer<vtkImageData> image;
  apctest::Render(
    grid,
    [&](vtkAPCVolumeMapper* m)
    {
      m->SetSampleDistance(0.02);
      m->ComputeSegmentCountOn();
      image = m->GetLastImage(); // filled by the one render below, kept alive by us
    },
    {}, view);
  ASSERT_NE(image->GetPointData()->GetArray("Moments"), nullptr);

  const std::string path = apctest::OutputPath("mapper_images.exr");
  vtkNew<vtkAPCEXRWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(image);
  ASSERT_EQ(writer->Write(), 1);

  Imf::InputFile file(path.c_str());
  const Imath::Box2i window = file.header().dataWindow();
  const int width = window.max.x - window.min.x + 1;
  const int height = window.max.y - window.min.y + 1;
  ASSERT_EQ(width, view.Width);
  ASSERT_EQ(height, view.Height);
  for (const char* channel :
    { "R", "A", "Moments.0", "Moments.4", "ColourSums.3", "SegmentCount.0" })
  {
    ASSERT_NE(file.header().channels().findChannel(channel), nullptr) << channel;
  }
  std::vector<float> alpha(static_cast<size_t>(width) * height);
  std::vector<float> b4(alpha.size());
  Imf::FrameBuffer frame;
  frame.insert("A",
    Imf::Slice(
      Imf::FLOAT, reinterpret_cast<char*>(alpha.data()), sizeof(float), sizeof(float) * width));
  frame.insert("Moments.4",
    Imf::Slice(
      Imf::FLOAT, reinterpret_cast<char*>(b4.data()), sizeof(float), sizeof(float) * width));
  file.setFrameBuffer(frame);
  file.readPixels(window.min.y, window.max.y);

  vtkDataArray* rgba = image->GetPointData()->GetArray("RGBA");
  vtkDataArray* moments = image->GetPointData()->GetArray("Moments");
  int visible = 0;
  for (int j = 0; j < height; ++j)
  {
    for (int i = 0; i < width; ++i)
    {
      const vtkIdType vtkPixel = static_cast<vtkIdType>(j) * width + i;
      const size_t exrPixel = static_cast<size_t>(height - 1 - j) * width + i; // top row first
      ASSERT_EQ(alpha[exrPixel], static_cast<float>(rgba->GetComponent(vtkPixel, 3)));
      ASSERT_EQ(b4[exrPixel], static_cast<float>(moments->GetComponent(vtkPixel, 4)));
      visible += alpha[exrPixel] > 0.1f;
    }
  }
  EXPECT_GT(visible, width * height / 10);
}
}
