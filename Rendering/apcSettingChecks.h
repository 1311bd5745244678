// SPDX-License-Identifier: BSD-3-Clause
// The one check of a setting, where it enters (a setter of vtkAPCVolumeMapper,
// vtkAPCCompositePass or ParaView's APC Volume): a value outside the setting's range is said
// once, in one warning naming the setting, its range and what is used instead, and clamped;
// nothing downstream checks or replaces it again. Processes set their settings alike (ParaView
// sets a property on every rank): the warning is said by the first process of the global
// controller only, not once per rank. Internal to APC.
#ifndef apcSettingChecks_h
#define apcSettingChecks_h

#include "vtkMultiProcessController.h"
#include "vtkObject.h"
#include "vtkSetGet.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace apc
{

// value clamped to [low, high] (NaN: low), with a warning on self if it was outside; meaning,
// if given, says what the range's ends mean ("0 picks the mean cell size").
template <class T>
T CheckedSetting(
  vtkObject* self, const char* name, T value, T low, T high, const char* meaning = nullptr)
{
  bool bad = value < low || value > high;
  if constexpr (std::is_floating_point_v<T>)
  {
    bad = bad || std::isnan(value);
  }
  if (!bad)
  {
    return value;
  }
  const T used = value > high ? high : low; // NaN compares false: low
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  if (controller && controller->GetLocalProcessId() != 0)
  {
    return used;
  }
  vtkWarningWithObjectMacro(self, << name << " must be in [" << low << ", " << high << "]"
                                  << (meaning ? " (" : "") << (meaning ? meaning : "")
                                  << (meaning ? ")" : "") << "; " << value << " was given, " << used
                                  << " is used.");
  return used;
}

// A setter's store: the (checked) value, and Modified() on self only when it changed.
template <class T>
void Assign(vtkObject* self, T& setting, T value)
{
  if (setting != value)
  {
    setting = value;
    self->Modified();
  }
}

} // namespace apc

#endif
