// The --spacing study of apcQualitySweep: the default sample distance against an exact render
// at a 4x finer lattice, in ParaView's default setup, with projected tetrahedra's own score.
#ifndef apcQualitySpacing_h
#define apcQualitySpacing_h

#include <string>

namespace apcbench
{
// Writes out/spacing.csv and out/spacing_<scene>_<case>.png; scenes: a comma list of
// wind, wind-close, flange, spheres, gearteeth (empty: all); cases: a comma list of the cases'
// names to render (empty: all; the reference's spacing still comes from every case, so the
// rows match a full run's). Returns the exit status.
int SpacingStudy(const std::string& data, const std::string& out, int size,
  const std::string& scenes, const std::string& cases = std::string());
}

#endif
