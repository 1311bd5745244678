// SPDX-License-Identifier: BSD-3-Clause
#include "apcCompositeFrame.h"

#include "vtkMultiProcessController.h"

#include <algorithm>

namespace apc
{

ProcessGroup::ProcessGroup(vtkMultiProcessController* controller, int displayProcess)
  : Controller(controller)
  , Parallel(controller && controller->GetNumberOfProcesses() > 1)
{
  if (this->Parallel)
  {
    this->Processes = controller->GetNumberOfProcesses();
    this->Rank = controller->GetLocalProcessId();
    this->Display = std::min(displayProcess, this->Processes - 1);
  }
}

} // namespace apc
