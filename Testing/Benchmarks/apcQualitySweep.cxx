// Image-quality sweep of vtkAPCVolumeMapper's MBOIT mode against its EXACT mode: for each
// scene, EXACT once and MBOIT for every overestimation beta x number of moments x resolve,
// compared (apc::CompareImages, data range 1) on the premultiplied RGB over black. Prints and
// writes CSV rows scene,beta,moments,resolve,ssim,psnr,mse,max_abs_diff, then the best
// setting by SSIM per scene and overall (mean SSIM over scenes), and where the paper's default
// (beta 0.3, 4 moments) ranks. Not run by ctest.
//
//   apcQualitySweep [--out DIR] [--data DIR] [--size S] [--scenes spheres,sandwich,...]
//
// DIR/quality.csv gets the rows, DIR/<scene>_exact.png the reference pictures and
// DIR/<scene>_b<beta>_m<moments>_<resolve>.png every MBOIT picture (over black, as compared).
//
//   apcQualitySweep --lattice [--out DIR] [--data DIR] [--size S] [--scenes ...]
//
// instead measures the sample lattice: EXACT and default MBOIT at the scene's spacing with and
// without the per-pixel lattice jitter, against the same mode at a 4x finer spacing (where
// banding is 4x finer and fainter): DIR/lattice.csv and DIR/lattice_<scene>_<case>.png.
//
//   apcQualitySweep --ranks [--out DIR] [--data DIR] [--size S] [--scenes ...]
//
// instead measures the Hybrid resolve against APC on split data: each scene's cells are cut
// into k = 1, 2, 4, 8 pieces of contiguous cell ids (for the puzzle scenes these follow the
// puzzle pieces, which interleave in depth; for the wind data its 8 Scotch pieces), each piece
// rendered by its own frame engine in this one process, as one rank would: pass 1 per piece,
// the pieces' moments summed (the allreduce, in double), pass 2 per piece, colour sums added
// (the reduce), resolved. APC (RENORMALISED) and HYBRID at 4 and 6 moments, beta 0.3, against
// the one-process EXACT image, with the wall and CPU time of pass 2 over all pieces (best of
// 5):
// DIR/ranks.csv and DIR/ranks_<scene>_k<k>_m<moments>_<resolve>.png.
//
//   apcQualitySweep --spacing [--out DIR] [--data DIR] [--size S] [--scenes ...]
//
// instead measures the default sample distance in ParaView's default setup against an exact
// render at a 4x finer lattice, with projected tetrahedra's own score (apcQualitySpacing.cxx):
// DIR/spacing.csv and DIR/spacing_<scene>_<case>.png.
//
//   apcQualitySweep --defaults [--out DIR]
//
// only writes DIR/defaults.csv: the mapper's default beta, moments and resolve, which the
// evaluation report compares every setting with.

#include "apcTestImages.h"
#include "apcTestPuzzles.h"
#include "apcTestRender.h"

#include "apcQualitySpacing.h"

#include "apcFrameEngine.h"
#include "apcImageMetrics.h"
#include "apcMomentParameters.h"
#include "apcResolve.h"
#include "vtkAPCPuzzleSource.h"
#include "vtkAPCVolumeMapper.h"
#include "vtkExtractCells.h"
#include "vtkIdList.h"
#include "vtkImageData.h"
#include "vtkPointData.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkXMLPUnstructuredGridReader.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <sys/resource.h>

#ifndef APC_SOURCE_DIR
#define APC_SOURCE_DIR "."
#endif

namespace
{

int kSize = 256; // --size
const double kBetas[] = { 0.0, 0.1, 0.25, 0.3, 0.5 };
const int kMoments[] = { 4, 6, 8 };
const int kResolves[] = { vtkAPCVolumeMapper::RENORMALISED, vtkAPCVolumeMapper::PAPER_SUM };

const char* ResolveName(int resolve)
{
  return resolve == vtkAPCVolumeMapper::PAPER_SUM ? "PAPER_SUM" : "RENORMALISED";
}

struct Row
{
  std::string Scene;
  double Beta = 0;
  int Moments = 0;
  int Resolve = 0;
  apc::ImageComparison C;
};

std::vector<apctest::Scene> MakeScenes(const std::string& data, const std::string& wanted)
{
  std::vector<apctest::Scene> scenes;
  // Synthetic scenes: the lattice spacing of TestVolumeMapperQuality.
  const apctest::View oblique = apctest::ObliqueView(kSize);
  scenes.push_back({ "spheres", apctest::PuzzleGrid(vtkAPCPuzzleSource::SPHERES, 4, 4, 32),
    apctest::SpheresTF(), oblique, 0.01 });
  // The spheres close up (TestVolumeMapperRegression's view): translucent shells filling the
  // picture in front of the opaque core, where a high beta tints the core.
  apctest::View close = oblique;
  close.Position = { 2.2, 1.5, 2.7 };
  close.ViewAngle = 30;
  scenes.push_back({ "spheres-close", apctest::PuzzleGrid(vtkAPCPuzzleSource::SPHERES, 4, 4, 32),
    apctest::SpheresTF(), close, 0.01 });
  scenes.push_back({ "sandwich", apctest::PuzzleGrid(vtkAPCPuzzleSource::SANDWICH, 3, 2, 24),
    apctest::SandwichTF(4), oblique, 0.01 });
  scenes.push_back({ "gearteeth", apctest::PuzzleGrid(vtkAPCPuzzleSource::SANDWICH, 4, 4, 24),
    apctest::SandwichTF(4), oblique, 0.01 });

  // OpenFOAM's windAroundBuildings, 8 Scotch pieces read as one grid; transfer function and
  // camera of TestVolumeMapperRegression's WindAroundBuildings test.
  vtkNew<vtkXMLPUnstructuredGridReader> reader;
  const std::string path = data + "/windAroundBuildings/wind.pvtu";
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkSmartPointer<vtkDataSet> wind = reader->GetOutputAsDataSet();
  if (!wind || wind->GetNumberOfCells() == 0 || !wind->GetPointData()->GetArray("U_mag"))
  {
    std::cerr << "error: could not read U_mag from " << path << "\n";
    std::exit(2);
  }
  wind->GetPointData()->SetActiveScalars("U_mag");
  scenes.push_back({ "wind", wind, apctest::WindTF(), apctest::WindView(kSize, kSize), 1.0 });
  if (!wanted.empty())
  {
    const std::string list = "," + wanted + ",";
    scenes.erase(std::remove_if(scenes.begin(), scenes.end(),
                   [&](const apctest::Scene& scene)
                   { return list.find("," + scene.Name + ",") == std::string::npos; }),
      scenes.end());
  }
  return scenes;
}

// The volume alone, premultiplied RGB over black, of one frame.
std::vector<float> RenderRGB(const apctest::Scene& scene, int mode, double beta, int moments,
  int resolve, double spacingFactor = 1.0, bool jitter = false)
{
  const apctest::Frame frame = apctest::Render(
    scene.Grid,
    [&](vtkAPCVolumeMapper* m)
    {
      m->SetMode(mode);
      m->SetSampleDistance(scene.SampleDistance * spacingFactor);
      m->SetLatticeJitter(jitter);
      m->SetOverestimation(beta);
      m->SetNumberOfMoments(moments);
      m->SetResolveMode(resolve);
    },
    scene.TF, scene.Camera);
  if (frame.RGBA.size() != static_cast<size_t>(4 * kSize * kSize))
  {
    std::cerr << "error: no image for " << scene.Name << "\n";
    std::exit(3);
  }
  return apc::CompositeOverBackground(frame.RGBA.data(), kSize, kSize, { 0, 0, 0 });
}

std::string Key(double beta, int moments, int resolve)
{
  std::ostringstream s;
  s << "beta=" << beta << " moments=" << moments << " resolve=" << ResolveName(resolve);
  return s.str();
}

std::string CsvLine(const Row& r)
{
  std::ostringstream s;
  s.precision(6);
  s << r.Scene << "," << r.Beta << "," << r.Moments << "," << ResolveName(r.Resolve) << ","
    << r.C.Ssim << ",";
  if (std::isinf(r.C.Psnr))
  {
    s << "inf";
  }
  else
  {
    s << r.C.Psnr;
  }
  s << "," << r.C.Mse << "," << r.C.MaxAbsDiff;
  return s.str();
}

void WriteRGBPNG(const std::vector<float>& rgb, const std::string& path)
{
  std::vector<float> rgba(4 * kSize * kSize);
  for (int p = 0; p < kSize * kSize; ++p)
  {
    std::copy_n(&rgb[3 * p], 3, &rgba[4 * p]);
    rgba[4 * p + 3] = 1.0f;
  }
  apctest::WritePNG(path, rgba, kSize, kSize);
}

// The --lattice study (see the top of the file).
int LatticeStudy(const std::vector<apctest::Scene>& scenes, const std::string& out)
{
  std::ofstream csv(out + "/lattice.csv");
  const std::string header = "scene,mode,jitter,ssim,psnr,mse,max_abs_diff";
  csv << header << "\n";
  std::cout << header << std::endl;
  for (const apctest::Scene& scene : scenes)
  {
    for (int mode : { vtkAPCVolumeMapper::EXACT, vtkAPCVolumeMapper::MBOIT })
    {
      const char* modeName = mode == vtkAPCVolumeMapper::EXACT ? "exact" : "mboit";
      const auto fine = RenderRGB(scene, mode, 0.3, 4, 0, 0.25);
      WriteRGBPNG(fine, out + "/lattice_" + scene.Name + "_" + modeName + "_fine.png");
      for (bool jitter : { false, true })
      {
        const auto coarse = RenderRGB(scene, mode, 0.3, 4, 0, 1.0, jitter);
        WriteRGBPNG(coarse,
          out + "/lattice_" + scene.Name + "_" + modeName + (jitter ? "_jitter" : "_fixed") +
            ".png");
        const apc::ImageComparison c =
          apc::CompareImages(coarse.data(), fine.data(), kSize, kSize, 3, 1.0, 16.0 / 255);
        std::ostringstream line;
        line << scene.Name << "," << modeName << "," << (jitter ? 1 : 0) << "," << c.Ssim << ","
             << c.Psnr << "," << c.Mse << "," << c.MaxAbsDiff;
        csv << line.str() << "\n";
        std::cout << line.str() << std::endl;
      }
    }
  }
  return 0;
}

// k pieces of contiguous cell ids (c * k / cells).
std::vector<vtkSmartPointer<vtkUnstructuredGrid>> SplitIds(vtkUnstructuredGrid* grid, int k)
{
  const vtkIdType cells = grid->GetNumberOfCells();
  std::vector<vtkSmartPointer<vtkUnstructuredGrid>> pieces;
  for (int p = 0; p < k; ++p)
  {
    vtkNew<vtkIdList> ids;
    for (vtkIdType c = p * cells / k; c < (p + 1) * cells / k; ++c)
    {
      ids->InsertNextId(c);
    }
    vtkNew<vtkExtractCells> extract;
    extract->SetInputData(grid);
    extract->SetCellList(ids);
    extract->Update();
    pieces.push_back(extract->GetOutput());
  }
  return pieces;
}

// One frame of the scene split into pieces, each rendered by its own mapper's frame engine
// as one rank would render it (see --ranks at the top).
struct SplitFrame
{
  std::vector<float> RGB;
  double Pass1Seconds = 0;
  double Pass2Seconds = 0;
  double Pass2CPUSeconds = 0; // user + system time of all threads: steadier on a busy machine
};

double ProcessCPUSeconds()
{
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + 1e-6 * usage.ru_utime.tv_usec + usage.ru_stime.tv_sec +
    1e-6 * usage.ru_stime.tv_usec;
}

SplitFrame RenderSplit(const apctest::Scene& scene,
  const std::vector<vtkSmartPointer<vtkUnstructuredGrid>>& pieces, int moments, int resolve)
{
  vtkNew<vtkRenderWindow> window;
  vtkNew<vtkRenderer> renderer;
  apctest::SetUpWindow(window, renderer, scene.Camera);
  apctest::ApplyView(renderer, scene.Camera);
  double bounds[6];
  scene.Grid->GetBounds(bounds);
  renderer->ResetCameraClippingRange(bounds);
  window->Render(); // the window and its (empty) depth buffer exist
  auto property = apctest::MakeVolumeProperty(scene.TF);

  apc::ImageSetup image;
  image.Width = kSize;
  image.Height = kSize;
  image.Aspect = 1.0;
  const std::vector<float> farDepth(static_cast<size_t>(kSize) * kSize, 1.0f);
  std::vector<vtkSmartPointer<vtkAPCVolumeMapper>> mappers;
  std::vector<vtkSmartPointer<vtkVolume>> volumes;
  std::vector<std::unique_ptr<apc::FrameEngine>> engines; // one per piece, as the pass keeps
  for (const auto& piece : pieces)
  {
    auto mapper = vtkSmartPointer<vtkAPCVolumeMapper>::New();
    mapper->SetInputData(piece);
    mapper->SetSampleDistance(scene.SampleDistance);
    mapper->SetOverestimation(apc::kDefaultOverestimation);
    mapper->SetNumberOfMoments(moments);
    mapper->SetResolveMode(resolve);
    auto volume = vtkSmartPointer<vtkVolume>::New();
    volume->SetMapper(mapper);
    volume->SetProperty(property);
    auto engine = std::make_unique<apc::FrameEngine>();
    engine->BeginFrame(mapper->GetVolumeSettings());
    if (!engine->UpdateInput(mapper->GetInput(), mapper))
    {
      std::cerr << "error: a piece of " << scene.Name << " cannot be rendered\n";
      std::exit(3);
    }
    mappers.push_back(mapper);
    volumes.push_back(volume);
    engines.push_back(std::move(engine));
  }
  // All pieces' cells and volume, as the pass agrees them (the default sample distance).
  apc::ExactSum volumeSum;
  for (const auto& engine : engines)
  {
    volumeSum.Add(engine->GetCellVolume());
  }
  for (const auto& engine : engines)
  {
    if (!engine->Prepare(renderer, property, bounds,
          static_cast<double>(scene.Grid->GetNumberOfCells()), volumeSum.Value(), farDepth.data(),
          image))
    {
      std::cerr << "error: a piece of " << scene.Name << " cannot be rendered\n";
      std::exit(3);
    }
  }
  const apc::MomentParameters parameters = mappers.front()->GetVolumeSettings().Moments;
  const size_t pixels = static_cast<size_t>(kSize) * kSize;
  const int stride = parameters.Moments + 1;
  using Clock = std::chrono::steady_clock;
  SplitFrame frame;
  std::vector<double> global(pixels * stride, 0.0);
  auto start = Clock::now();
  for (auto& engine : engines)
  {
    engine->RenderMoments(parameters, global.data());
  }
  frame.Pass1Seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::vector<double> colour;
  frame.Pass2Seconds = 1e300;
  frame.Pass2CPUSeconds = 1e300;
  for (int repeat = 0; repeat < 5; ++repeat)
  {
    colour.assign(pixels * 4, 0.0);
    start = Clock::now();
    const double cpu = ProcessCPUSeconds();
    for (auto& engine : engines)
    {
      engine->RenderColour(parameters, global.data(), colour.data());
    }
    frame.Pass2CPUSeconds = std::min(frame.Pass2CPUSeconds, ProcessCPUSeconds() - cpu);
    frame.Pass2Seconds =
      std::min(frame.Pass2Seconds, std::chrono::duration<double>(Clock::now() - start).count());
  }
  std::vector<float> rgba(4 * pixels, 0.0f);
  apc::ResolveImage(parameters.Resolve, pixels, global.data(), stride, colour.data(), rgba.data());
  frame.RGB = apc::CompositeOverBackground(rgba.data(), kSize, kSize, { 0, 0, 0 });
  return frame;
}

// The --ranks study (see the top of the file).
int RanksStudy(const std::vector<apctest::Scene>& scenes, const std::string& out)
{
  std::ofstream csv(out + "/ranks.csv");
  const std::string header =
    "scene,ranks,moments,resolve,ssim,psnr,mse,max_abs_diff,pass1_s,pass2_s,pass2_cpu_s";
  csv << header << "\n";
  std::cout << header << std::endl;
  for (const apctest::Scene& scene : scenes)
  {
    vtkUnstructuredGrid* grid = vtkUnstructuredGrid::SafeDownCast(scene.Grid);
    if (!grid)
    {
      std::cerr << "error: " << scene.Name << " is not an unstructured grid\n";
      return 3;
    }
    const auto exact = RenderRGB(scene, vtkAPCVolumeMapper::EXACT, 0.3, 4, 0);
    WriteRGBPNG(exact, out + "/ranks_" + scene.Name + "_exact.png");
    for (int k : { 1, 2, 4, 8 })
    {
      const auto pieces = SplitIds(grid, k);
      for (int moments : { 4, 6 })
      {
        for (int resolve : { vtkAPCVolumeMapper::RENORMALISED, vtkAPCVolumeMapper::HYBRID })
        {
          const SplitFrame frame = RenderSplit(scene, pieces, moments, resolve);
          const apc::ImageComparison c =
            apc::CompareImages(frame.RGB.data(), exact.data(), kSize, kSize, 3, 1.0, 16.0 / 255);
          const char* name = resolve == vtkAPCVolumeMapper::HYBRID ? "HYBRID" : "APC";
          std::ostringstream line;
          line.precision(6);
          line << scene.Name << "," << k << "," << moments << "," << name << "," << c.Ssim << ",";
          if (std::isinf(c.Psnr))
          {
            line << "inf";
          }
          else
          {
            line << c.Psnr;
          }
          line << "," << c.Mse << "," << c.MaxAbsDiff << "," << frame.Pass1Seconds << ","
               << frame.Pass2Seconds << "," << frame.Pass2CPUSeconds;
          csv << line.str() << "\n";
          std::cout << line.str() << std::endl;
          std::ostringstream png;
          png << out << "/ranks_" << scene.Name << "_k" << k << "_m" << moments << "_" << name
              << ".png";
          WriteRGBPNG(frame.RGB, png.str());
        }
      }
    }
  }
  return 0;
}

// The mapper's defaults as a default-constructed mapper has them, for the report (it compares
// every setting with the default one and must not drift from the code).
int WriteDefaults(const std::string& out)
{
  vtkNew<vtkAPCVolumeMapper> mapper;
  const int resolve = mapper->GetResolveMode();
  std::ofstream csv(out + "/defaults.csv");
  csv << "beta,moments,resolve\n"
      << mapper->GetOverestimation() << "," << mapper->GetNumberOfMoments() << ","
      << (resolve == vtkAPCVolumeMapper::HYBRID ? "HYBRID" : ResolveName(resolve)) << "\n";
  return csv ? 0 : 1;
}
} // namespace

int main(int argc, char* argv[])
{
  std::string out = ".";
  std::string data = APC_SOURCE_DIR "/Data";
  std::string wanted;
  std::string cases; // --cases: the spacing study's cases to render (all if empty)
  bool lattice = false;
  bool ranks = false;
  bool defaults = false;
  bool spacing = false;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (arg == "--lattice")
    {
      lattice = true;
    }
    else if (arg == "--spacing")
    {
      spacing = true;
    }
    else if (arg == "--defaults")
    {
      defaults = true;
    }
    else if (arg == "--ranks")
    {
      ranks = true;
    }
    else if ((arg == "--out" || arg == "--data" || arg == "--scenes") && i + 1 < argc)
    {
      (arg == "--out" ? out : arg == "--data" ? data : wanted) = argv[++i];
    }
    else if (arg == "--cases" && i + 1 < argc)
    {
      cases = argv[++i];
    }
    else if (arg == "--size" && i + 1 < argc && std::atoi(argv[i + 1]) >= 16)
    {
      kSize = std::atoi(argv[++i]);
    }
    else
    {
      std::cerr << "usage: apcQualitySweep [--lattice | --ranks | --spacing | --defaults] [--out "
                   "DIR] [--data "
                   "DIR] [--size S >= 16] "
                   "[--scenes spheres,spheres-close,sandwich,gearteeth,wind] [--cases "
                   "mboit-default,...]\n";
      return 1;
    }
  }
  std::filesystem::create_directories(out);
  if (defaults)
  {
    return WriteDefaults(out);
  }
  const auto start = std::chrono::steady_clock::now();
  if (lattice)
  {
    return LatticeStudy(MakeScenes(data, wanted), out);
  }
  if (ranks)
  {
    return RanksStudy(MakeScenes(data, wanted), out);
  }
  if (spacing)
  {
    return apcbench::SpacingStudy(data, out, kSize, wanted, cases);
  }

  std::ofstream csv(out + "/quality.csv");
  const std::string header = "scene,beta,moments,resolve,ssim,psnr,mse,max_abs_diff";
  csv << header << "\n";
  std::cout << header << std::endl;

  std::vector<Row> rows;
  const std::vector<apctest::Scene> scenes = MakeScenes(data, wanted);
  if (scenes.empty())
  {
    std::cerr << "error: no scene matches --scenes " << wanted << "\n";
    return 1;
  }
  for (const apctest::Scene& scene : scenes)
  {
    const auto exact = RenderRGB(scene, vtkAPCVolumeMapper::EXACT, 0.3, 4, 0);
    // PNGs for a look, over black like the comparison.
    auto writePNG = [&](const std::vector<float>& rgb, const std::string& name)
    { WriteRGBPNG(rgb, out + "/" + name + ".png"); };
    writePNG(exact, scene.Name + "_exact");
    for (double beta : kBetas)
    {
      for (int moments : kMoments)
      {
        for (int resolve : kResolves)
        {
          const auto mboit = RenderRGB(scene, vtkAPCVolumeMapper::MBOIT, beta, moments, resolve);
          Row row{ scene.Name, beta, moments, resolve,
            apc::CompareImages(mboit.data(), exact.data(), kSize, kSize, 3, 1.0, 16.0 / 255) };
          std::ostringstream name;
          name << scene.Name << "_b" << beta << "_m" << moments << "_" << ResolveName(resolve);
          writePNG(mboit, name.str());
          const std::string line = CsvLine(row);
          csv << line << "\n";
          std::cout << line << std::endl;
          rows.push_back(row);
        }
      }
    }
  }

  std::cout << "\nbest by SSIM per scene (rank of the paper's default beta=0.3, 4 moments):\n";
  std::map<std::string, double> meanSsim;
  for (const apctest::Scene& scene : scenes)
  {
    std::vector<Row> sorted;
    for (const Row& r : rows)
    {
      if (r.Scene == scene.Name)
      {
        sorted.push_back(r);
        meanSsim[Key(r.Beta, r.Moments, r.Resolve)] += r.C.Ssim / scenes.size();
      }
    }
    std::stable_sort(
      sorted.begin(), sorted.end(), [](const Row& a, const Row& b) { return a.C.Ssim > b.C.Ssim; });
    const Row& best = sorted.front();
    std::cout << scene.Name << ": best " << Key(best.Beta, best.Moments, best.Resolve) << " SSIM "
              << best.C.Ssim << ", PSNR " << best.C.Psnr << " dB\n";
    for (size_t k = 0; k < sorted.size(); ++k)
    {
      if (sorted[k].Moments == 4 && std::abs(sorted[k].Beta - 0.3) < 1e-12)
      {
        std::cout << "  paper default " << ResolveName(sorted[k].Resolve) << ": rank " << k + 1
                  << " of " << sorted.size() << ", SSIM " << sorted[k].C.Ssim << "\n";
      }
    }
  }

  std::vector<std::pair<std::string, double>> overall(meanSsim.begin(), meanSsim.end());
  std::stable_sort(overall.begin(), overall.end(),
    [](const auto& a, const auto& b) { return a.second > b.second; });
  std::cout << "\noverall best by mean SSIM over " << scenes.size()
            << " scenes: " << overall.front().first << " mean SSIM " << overall.front().second
            << "\n";
  for (size_t k = 0; k < overall.size(); ++k)
  {
    if (overall[k].first.find("beta=0.3 moments=4 ") == 0)
    {
      std::cout << "  paper default " << overall[k].first << ": rank " << k + 1 << " of "
                << overall.size() << ", mean SSIM " << overall[k].second << "\n";
    }
  }
  const double seconds =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "\nwrote " << out << "/quality.csv (" << rows.size() << " rows) in " << seconds
            << " s\n";
  return 0;
}
