// SPDX-License-Identifier: BSD-3-Clause
// A Catalyst adaptor as a simulation code writes one (ParaView 5.11's legacy Catalyst API, the
// one Debian ships): start Catalyst with a Python analysis script, ask it at every time step
// whether it wants the data, hand over the grids only then, stop it at the end. Nothing here
// knows about APC: the script loads the plugin and picks the representation.
#ifndef apcCatalystAdaptor_h
#define apcCatalystAdaptor_h

#include <mpi.h>

#include <functional>
#include <string>
#include <vector>

#include "vtkNew.h"

class vtkCPDataDescription;
class vtkCPProcessor;
class vtkDataObject;

namespace apc
{
class CatalystAdaptor
{
public:
  // Gives the grid of one channel (the name the script's TrivialProducer is registered with).
  using GridProvider = std::function<vtkDataObject*(const std::string& channel)>;

  CatalystAdaptor();
  ~CatalystAdaptor();

  /**
   * Starts Catalyst on all ranks of MPI_COMM_WORLD with one Python script (a ParaView 5.9+
   * "v2" script: catalyst_execute(info), catalyst.Options(); version 1 scripts work too) and
   * the channels the simulation offers. Collective. Returns false on every rank, with error
   * set, when the script is missing or Catalyst could not set it up on some rank.
   */
  bool Initialize(
    const std::string& script, const std::vector<std::string>& channels, std::string& error);

  /**
   * One time step: asks the script's triggers whether step / time is to be processed (every
   * Nth step, a time interval...) and only then builds the grids (provider) and runs the
   * pipeline. last forces output. Collective. Returns 1 if processed, 0 if skipped, -1 if the
   * pipeline failed on some rank (every rank returns -1).
   */
  int CoProcess(double time, long step, bool last, const GridProvider& provider);

  // Stops Catalyst (the script's catalyst_finalize runs). Collective; safe to call twice.
  void Finalize();

private:
  vtkNew<vtkCPProcessor> Processor;
  vtkNew<vtkCPDataDescription> Description;
  std::vector<std::string> Channels;
  bool Started = false;
};
}

#endif
