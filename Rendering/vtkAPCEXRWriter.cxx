// SPDX-License-Identifier: BSD-3-Clause
#include "vtkAPCEXRWriter.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkAPCEXRWriter);

//------------------------------------------------------------------------------
vtkAPCEXRWriter::~vtkAPCEXRWriter()
{
  this->SetFileName(nullptr);
}

//------------------------------------------------------------------------------
int vtkAPCEXRWriter::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkImageData");
  return 1;
}

//------------------------------------------------------------------------------
void vtkAPCEXRWriter::WriteData()
{
  vtkImageData* image = vtkImageData::SafeDownCast(this->GetInput());
  if (!image || !this->FileName)
  {
    vtkErrorMacro("Need a vtkImageData input and a FileName.");
    return;
  }
  int dims[3];
  image->GetDimensions(dims);
  if (dims[0] < 1 || dims[1] < 1 || dims[2] != 1)
  {
    vtkErrorMacro("Only 2D images can be written to EXR (dimensions " << dims[0] << " x " << dims[1]
                                                                      << " x " << dims[2] << ").");
    return;
  }
  const int width = dims[0];
  const int height = dims[1];
  const size_t pixels = static_cast<size_t>(width) * height;

  // One contiguous float plane per channel, flipped vertically.
  std::vector<std::string> names;
  std::vector<std::vector<float>> planes;
  vtkPointData* pd = image->GetPointData();
  for (int a = 0; a < pd->GetNumberOfArrays(); ++a)
  {
    vtkDataArray* array = pd->GetArray(a);
    if (!array || !array->GetName() || array->GetNumberOfTuples() != static_cast<vtkIdType>(pixels))
    {
      continue;
    }
    const std::string name = array->GetName();
    const int components = array->GetNumberOfComponents();
    for (int c = 0; c < components; ++c)
    {
      names.push_back(name == "RGBA" && components == 4 ? std::string(1, "RGBA"[c])
                                                        : name + "." + std::to_string(c));
      std::vector<float> plane(pixels);
      for (int j = 0; j < height; ++j)
      {
        for (int i = 0; i < width; ++i)
        {
          plane[static_cast<size_t>(height - 1 - j) * width + i] =
            static_cast<float>(array->GetComponent(static_cast<vtkIdType>(j) * width + i, c));
        }
      }
      planes.push_back(std::move(plane));
    }
  }
  if (names.empty())
  {
    vtkErrorMacro("The image has no point arrays to write.");
    return;
  }

  try
  {
    Imf::Header header(width, height);
    Imf::FrameBuffer frame;
    for (size_t c = 0; c < names.size(); ++c)
    {
      header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
      frame.insert(names[c],
        Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[c].data()), sizeof(float),
          sizeof(float) * width));
    }
    Imf::OutputFile file(this->FileName, header);
    file.setFrameBuffer(frame);
    file.writePixels(height);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Could not write " << this->FileName << ": " << e.what());
    std::remove(this->FileName);
  }
}

//------------------------------------------------------------------------------
void vtkAPCEXRWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
}
