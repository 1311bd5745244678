// SPDX-License-Identifier: BSD-3-Clause
#include "apcCatalystAdaptor.h"

#include "vtkCPDataDescription.h"
#include "vtkCPInputDataDescription.h"
#include "vtkCPProcessor.h"
#include "vtkCPPythonPipeline.h"
#include "vtkDataObject.h"

#include <fstream>

namespace apc
{
namespace
{
// Catalyst's calls are collective: a failure on one rank must stop all of them, or the others
// wait forever in the next render.
bool AllRanksOk(bool ok)
{
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all == 1;
}
}

CatalystAdaptor::CatalystAdaptor() = default;

CatalystAdaptor::~CatalystAdaptor()
{
  this->Finalize();
}

bool CatalystAdaptor::Initialize(
  const std::string& script, const std::vector<std::string>& channels, std::string& error)
{
  if (!AllRanksOk(std::ifstream(script).good()))
  {
    error = "cannot read the Catalyst script " + script;
    return false;
  }
  if (!AllRanksOk(this->Processor->Initialize() != 0))
  {
    error = "Catalyst did not start";
    return false;
  }
  this->Started = true;
  // Detects the script's version (v2: catalyst_execute) and sets it up; nullptr on failure.
  auto pipeline = vtkCPPythonPipeline::CreateAndInitializePipeline(script.c_str());
  if (!AllRanksOk(pipeline != nullptr))
  {
    error = "Catalyst could not set up the script " + script + " (see the Python error above)";
    this->Finalize();
    return false;
  }
  this->Processor->AddPipeline(pipeline);
  this->Channels = channels;
  for (const auto& channel : channels)
  {
    this->Description->AddInput(channel.c_str());
  }
  return true;
}

int CatalystAdaptor::CoProcess(double time, long step, bool last, const GridProvider& provider)
{
  if (!this->Started)
  {
    return -1;
  }
  this->Description->SetTimeData(time, step);
  this->Description->SetForceOutput(last);
  // The same answer on every rank: the triggers depend on step and time only.
  if (this->Processor->RequestDataDescription(this->Description) == 0)
  {
    return 0;
  }
  for (const auto& channel : this->Channels)
  {
    vtkCPInputDataDescription* input =
      this->Description->GetInputDescriptionByName(channel.c_str());
    if (input && this->Description->GetIfGridIsNecessary(channel.c_str()))
    {
      input->SetGrid(provider(channel));
    }
  }
  if (!AllRanksOk(this->Processor->CoProcess(this->Description) != 0))
  {
    return -1;
  }
  return 1;
}

void CatalystAdaptor::Finalize()
{
  if (this->Started)
  {
    this->Processor->Finalize();
    this->Started = false;
  }
}
}
