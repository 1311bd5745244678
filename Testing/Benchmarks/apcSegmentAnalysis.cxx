// What exact sort-last compositing of segments would move, against APC's fixed payload, in
// one process: for each configuration the ranks' pieces are rendered one after the other
// into their segment lists, exactly as vtkAPCCompositePass's SEGMENTS mode renders them on
// each rank (same mapper stage API, global bounds, sample lattice and screen rectangle), and
// apc::CountSegmentTransfer counts direct send to the strip owners and binary swap (computed:
// the paper's table, "average number of segments transferred per non-empty pixel").
//
//   apcSegmentAnalysis --out DIR [--data DIR] [--size S] [--wind-size W H]
//                      [--gear-ranks 1,2,4,8] [--wind-ranks 2,4,8] [--wind-distances 0.6,1,1.6]
//
// Configurations: the gear teeth of apcScalingBenchmark (one piece per rank, 4 orbit cameras)
// and the real wind data (8 Scotch pieces shared out to the ranks as ParaView's reader does,
// the camera of paraview_vs_apc.py moved to each distance factor along its line of sight).
// Writes (creating DIR) DIR/segment_transfer.csv and, for the first camera of each configuration,
// the per-pixel segment count over all ranks as DIR/heatmap_<case>_np<N>.pgm (16-bit binary PGM,
// top row first). APC's bytes are the pass's payload for the same rectangle: every rank sends
// (moments + 1 + 4 colour) doubles per pixel, the display rank also 4 bytes of depth.
// Not run by ctest; run-evaluation.sh runs it.

#include "apcFrameEngine.h"
#include "apcGearTeethScene.h"
#include "apcSegmentTransfer.h"
#include "apcTestScenes.h"
#include "vtkAPCCompositePass.h"
#include "vtkAPCVolumeMapper.h"

#include "vtkCamera.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkXMLPUnstructuredGridReader.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#ifndef APC_SOURCE_DIR
#define APC_SOURCE_DIR "."
#endif

namespace
{
// Bytes of one segment on the wire (vtkAPCCompositePass's WireSegment).
constexpr int kSegmentBytes = 24;

std::vector<double> ParseList(const char* text)
{
  std::vector<double> values;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ','))
  {
    values.push_back(std::atof(item.c_str()));
  }
  return values;
}

struct Config
{
  std::string Case;
  int Ranks = 1;
  std::string Camera;
  bool Heatmap = false;
};

// Renders each rank's segments with the pass's frame set-up and counts the transfers.
class Analysis
{
public:
  Analysis(int width, int height)
    : Width(width)
    , Height(height)
  {
    this->Window->SetOffScreenRendering(1);
    this->Window->SetSize(width, height);
    this->Window->AddRenderer(this->Renderer);
    this->Window->Render(); // a GL context for the mapper's set-up
  }

  vtkRenderer* GetRenderer() { return this->Renderer; }

  // pieces[r]: rank r's cells; volume carries the transfer function.
  std::string Run(const Config& config,
    const std::vector<vtkSmartPointer<vtkUnstructuredGrid>>& pieces, vtkVolume* volume,
    vtkAPCVolumeMapper* mapper, const double bounds[6], const std::string& out)
  {
    std::vector<float> depth(static_cast<size_t>(this->Width) * this->Height, 1.0f);
    std::vector<apc::SegmentImage> images(pieces.size());
    for (size_t r = 0; r < pieces.size(); ++r)
    {
      mapper->SetInputData(pieces[r]);
      apc::FrameEngine* engine = mapper->GetFrameEngine();
      engine->BeginFrame();
      if (engine->UpdateInput(mapper) &&
        engine->Prepare(mapper, this->Renderer, volume, bounds, depth.data(),
          apc::ImageSetup::FullQuality(this->Renderer)))
      {
        engine->RenderSegments(images[r]);
      }
      if (images[r].Width != this->Width || images[r].Height != this->Height)
      {
        images[r].Reset(this->Width, this->Height); // an empty rank
      }
    }
    std::vector<const apc::SegmentImage*> ranks;
    for (const auto& image : images)
    {
      ranks.push_back(&image);
    }
    int rect[4];
    vtkAPCCompositePass::GetScreenRectangle(
      this->Renderer, bounds, this->Width, this->Height, rect);
    const apc::SegmentTransferCounts c = apc::CountSegmentTransfer(ranks, rect[1], rect[3]);
    const long long rectPixels =
      static_cast<long long>(rect[2] - rect[0]) * static_cast<long long>(rect[3] - rect[1]);
    const int n = config.Ranks;
    const double apcBytes =
      n > 1 ? rectPixels * (8.0 * n * (mapper->GetNumberOfMoments() + 1 + 4) + 4.0) : 0.0;

    std::string heatmap;
    if (config.Heatmap)
    {
      heatmap = "heatmap_" + config.Case + "_np" + std::to_string(n) + ".pgm";
      WriteHeatmap(out + "/" + heatmap, apc::SegmentCountImage(ranks));
    }
    char line[1024];
    std::snprintf(line, sizeof(line),
      "%s,%d,%s,%d,%d,%lld,%lld,%lld,%.4f,%lld,%lld,%lld,%lld,%.0f,%.0f,%.0f,%s\n",
      config.Case.c_str(), n, config.Camera.c_str(), this->Width, this->Height, rectPixels,
      static_cast<long long>(c.NonEmptyPixels), static_cast<long long>(c.Segments),
      c.PerNonEmptyPixel(c.Segments), static_cast<long long>(c.MaxSegmentsPerPixel),
      static_cast<long long>(c.DirectSend), static_cast<long long>(c.BinarySwap),
      static_cast<long long>(c.BinarySwapUnmerged), apcBytes,
      static_cast<double>(kSegmentBytes) * c.DirectSend,
      c.BinarySwap < 0 ? -1.0 : static_cast<double>(kSegmentBytes) * c.BinarySwap, heatmap.c_str());
    std::printf("%s %d ranks, camera %s: %.2f segments per non-empty pixel (max %lld); "
                "transferred per non-empty pixel: direct send %.2f, binary swap %.2f\n",
      config.Case.c_str(), n, config.Camera.c_str(), c.PerNonEmptyPixel(c.Segments),
      static_cast<long long>(c.MaxSegmentsPerPixel), c.PerNonEmptyPixel(c.DirectSend),
      c.BinarySwap < 0 ? -1.0 : c.PerNonEmptyPixel(c.BinarySwap));
    std::fflush(stdout);
    return line;
  }

private:
  void WriteHeatmap(const std::string& path, const std::vector<int32_t>& counts) const
  {
    std::ofstream f(path, std::ios::binary);
    f << "P5\n" << this->Width << " " << this->Height << "\n65535\n";
    for (int j = this->Height - 1; j >= 0; --j)
    {
      for (int i = 0; i < this->Width; ++i)
      {
        const int32_t v =
          std::min<int32_t>(counts[static_cast<size_t>(j) * this->Width + i], 65535);
        const unsigned char bytes[2] = { static_cast<unsigned char>(v >> 8),
          static_cast<unsigned char>(v & 255) };
        f.write(reinterpret_cast<const char*>(bytes), 2);
      }
    }
  }

  int Width;
  int Height;
  vtkNew<vtkRenderWindow> Window;
  vtkNew<vtkRenderer> Renderer;
};

void Usage(const char* program)
{
  std::fprintf(stderr,
    "usage: %s --out DIR [--data DIR] [--size S] [--wind-size W H] [--gear-ranks 1,2,4,8]\n"
    "          [--wind-ranks 2,4,8] [--wind-distances 0.6,1,1.6]\n",
    program);
}
}

int main(int argc, char* argv[])
{
  std::string out;
  std::string data = std::string(APC_SOURCE_DIR) + "/Data";
  int size = 512;
  int windWidth = 1024;
  int windHeight = 1024;
  std::vector<double> gearRanks = { 1, 2, 4, 8 };
  std::vector<double> windRanks = { 2, 4, 8 };
  std::vector<double> distances = { 0.6, 1.0, 1.6 };
  for (int a = 1; a < argc; ++a)
  {
    const bool hasValue = a + 1 < argc;
    if (!std::strcmp(argv[a], "--out") && hasValue)
    {
      out = argv[++a];
    }
    else if (!std::strcmp(argv[a], "--data") && hasValue)
    {
      data = argv[++a];
    }
    else if (!std::strcmp(argv[a], "--size") && hasValue)
    {
      size = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--wind-size") && a + 2 < argc)
    {
      windWidth = std::atoi(argv[++a]);
      windHeight = std::atoi(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--gear-ranks") && hasValue)
    {
      gearRanks = ParseList(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--wind-ranks") && hasValue)
    {
      windRanks = ParseList(argv[++a]);
    }
    else if (!std::strcmp(argv[a], "--wind-distances") && hasValue)
    {
      distances = ParseList(argv[++a]);
    }
    else
    {
      Usage(argv[0]);
      return 2;
    }
  }
  if (out.empty() || size < 1 || windWidth < 1 || windHeight < 1)
  {
    Usage(argv[0]);
    return 2;
  }
  std::error_code made;
  std::filesystem::create_directories(out, made);
  if (made)
  {
    std::cerr << "error: cannot create " << out << ": " << made.message() << "\n";
    return 1;
  }

  std::ostringstream rows;
  rows << "case,ranks,camera,width,height,rect_pixels,nonempty_pixels,segments,"
          "avg_segments_per_pixel,max_segments_per_pixel,direct_send_segments,"
          "binary_swap_segments,binary_swap_unmerged_segments,apc_bytes,direct_send_bytes,"
          "binary_swap_bytes,heatmap\n";

  // The gear teeth, as apcScalingBenchmark renders them.
  {
    Analysis analysis(size, size);
    for (double value : gearRanks)
    {
      const int n = static_cast<int>(value);
      std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
      for (int r = 0; r < n; ++r)
      {
        pieces.push_back(apcbench::GearTeethPiece(r, n));
      }
      vtkNew<vtkAPCVolumeMapper> mapper;
      vtkNew<vtkVolume> volume;
      apcbench::ConfigureGearTeethVolume(volume, mapper, n);
      for (int camera = 0; camera < 4; ++camera)
      {
        apcbench::SetGearTeethCamera(analysis.GetRenderer(), camera);
        rows << analysis.Run({ "gearteeth", n, std::to_string(camera), camera == 0 }, pieces,
          volume, mapper, apcbench::kGearBounds, out);
      }
    }
  }

  // The wind data, pieces per rank as vtkXMLPUnstructuredGridReader gives them.
  {
    const std::string path = data + "/windAroundBuildings/wind.pvtu";
    Analysis analysis(windWidth, windHeight);
    const apctest::View view = apctest::WindView(windWidth, windHeight);
    const apctest::TransferFunction tf = apctest::WindTF();
    for (double value : windRanks)
    {
      const int n = static_cast<int>(value);
      std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
      double bounds[6] = { 1e300, -1e300, 1e300, -1e300, 1e300, -1e300 };
      for (int r = 0; r < n; ++r)
      {
        vtkNew<vtkXMLPUnstructuredGridReader> reader;
        reader->SetFileName(path.c_str());
        reader->UpdatePiece(r, n, 0);
        vtkSmartPointer<vtkUnstructuredGrid> piece = reader->GetOutput();
        if (!piece || !piece->GetPointData()->GetArray("U_mag"))
        {
          std::cerr << "error: could not read U_mag from " << path << "\n";
          return 1;
        }
        piece->GetPointData()->SetActiveScalars("U_mag");
        double b[6];
        piece->GetBounds(b);
        for (int d = 0; d < 3; ++d)
        {
          bounds[2 * d] = std::min(bounds[2 * d], b[2 * d]);
          bounds[2 * d + 1] = std::max(bounds[2 * d + 1], b[2 * d + 1]);
        }
        pieces.push_back(piece);
      }
      // The transfer function of apctest::WindTF (paraview_vs_apc.py's opacity).
      vtkNew<vtkAPCVolumeMapper> mapper;
      vtkNew<vtkVolume> volume;
      volume->SetMapper(mapper);
      volume->SetProperty(apctest::MakeVolumeProperty(tf));
      for (size_t d = 0; d < distances.size(); ++d)
      {
        vtkCamera* camera = analysis.GetRenderer()->GetActiveCamera();
        double position[3];
        for (int k = 0; k < 3; ++k)
        {
          position[k] = view.FocalPoint[k] + distances[d] * (view.Position[k] - view.FocalPoint[k]);
        }
        camera->SetFocalPoint(view.FocalPoint.data());
        camera->SetPosition(position);
        camera->SetViewUp(view.ViewUp.data());
        camera->SetViewAngle(view.ViewAngle);
        camera->ParallelProjectionOff();
        analysis.GetRenderer()->ResetCameraClippingRange(bounds);
        char label[32];
        std::snprintf(label, sizeof(label), "%g", distances[d]);
        rows << analysis.Run(
          { "wind-" + std::string(label), n, label, true }, pieces, volume, mapper, bounds, out);
      }
    }
  }

  const std::string csv = out + "/segment_transfer.csv";
  std::ofstream file(csv);
  file << rows.str();
  if (!file)
  {
    std::cerr << "error: cannot write " << csv << "\n";
    return 1;
  }
  std::printf("wrote %s\n", csv.c_str());
  return 0;
}
