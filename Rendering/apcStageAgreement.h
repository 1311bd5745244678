// SPDX-License-Identifier: BSD-3-Clause
// A frame's local stage (work a process does on its own between two collectives: preparing
// its engines, pass 1, pass 2) run inside the frame's failure agreement. A stage that throws
// on one process (its memory ran out) must not leave the others waiting forever in the next
// collective, nor escape into the application: the stage runs in try/catch, and every
// process then joins one small MAX allreduce of its status (the failing rank), so that all
// of them leave the frame at the same point with the same message, which names the first
// failing process and its error (sent by it to the others only when a stage failed).
#ifndef apcStageAgreement_h
#define apcStageAgreement_h

#include "APCRenderingModule.h" // for export macro
#include "apcCompositeFrame.h"

#include <exception>
#include <string>
#include <utility>

namespace apc
{

// What work threw (its message), empty if it returned.
template <class F>
std::string CatchFailure(F&& work)
{
  try
  {
    work();
  }
  catch (const std::exception& e)
  {
    return *e.what() ? e.what() : "an unnamed exception";
  }
  catch (...)
  {
    return "an exception that is not a std::exception";
  }
  return std::string();
}

// Agrees whether this process's stage failed (failure: its error, empty if it did not) on
// every process. Empty if no process failed; otherwise "<what> failed on process N: <its
// error>", the same on every process (N the lowest failing rank).
APCRENDERING_EXPORT std::string AgreeOnFailure(
  const ProcessGroup& group, const char* stage, const char* what, const std::string& failure);

// AgreeOnFailure for a stage of the frame record describes: true if no process failed,
// otherwise record.Failed and record.Problem are set.
inline bool AgreeOnStage(const ProcessGroup& group, const char* stage, const char* what,
  const std::string& failure, FrameRecord& record)
{
  std::string problem = AgreeOnFailure(group, stage, what, failure);
  if (problem.empty())
  {
    return true;
  }
  record.Failed = true;
  record.Problem = std::move(problem);
  return false;
}

// Runs work (this process's part of a stage) and agrees on its outcome (AgreeOnStage).
template <class F>
bool RunAgreedStage(
  const ProcessGroup& group, const char* stage, const char* what, FrameRecord& record, F&& work)
{
  return AgreeOnStage(group, stage, what, CatchFailure(work), record);
}

} // namespace apc

#endif
