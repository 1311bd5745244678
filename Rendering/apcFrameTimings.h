// SPDX-License-Identifier: BSD-3-Clause
// What vtkAPCCompositePass reports of a frame: every process's render and wait times brought to
// the display process, and the frame record turned into the pass's named timings
// (vtkAPCCompositePass::Timings) and its verbose line. Internal to APC's rendering module.
#ifndef apcFrameTimings_h
#define apcFrameTimings_h

#include "apcCompositeFrame.h"
#include "vtkAPCCompositePass.h"

#include <string>

namespace apc
{

// A process's render seconds in the frame: its stages that render (no collective in them).
double RenderSeconds(const StageClock& clock);

// Every process's render seconds and its wait in the frame's collectives so far, into
// record.RankRender and RankWait on the display process (this process's own elsewhere): one
// gather, the stage "ranks". Every process calls it, after the mode's stages.
void GatherRankTimes(const ProcessGroup& group, FrameRecord& record);

// The record's stages, their collectives' waits and transfers, counts and the processes'
// render times, by the pass's names (Mode and ImageReduction are the pass's to set).
vtkAPCCompositePass::Timings TimingsOf(const FrameRecord& record);

// " stage s (wait w, transfer t), ... render per rank r0 r1 ... s,": the verbose line's part.
std::string DescribeStages(const FrameRecord& record);

} // namespace apc

#endif
