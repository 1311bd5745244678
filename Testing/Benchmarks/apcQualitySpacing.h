// The --spacing study of apcQualitySweep: the default sample distance against an exact render
// at a 4x finer lattice, in ParaView's default setup, with projected tetrahedra's own score.
#ifndef apcQualitySpacing_h
#define apcQualitySpacing_h

#include <string>

namespace apcbench
{
// Writes out/spacing.csv and out/spacing_<scene>_<case>.png; scenes: a comma list of
// wind, wind-close, flange, spheres, gearteeth (empty: all). Returns the exit status.
int SpacingStudy(
  const std::string& data, const std::string& out, int size, const std::string& scenes);
}

#endif
