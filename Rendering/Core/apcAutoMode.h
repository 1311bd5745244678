// SPDX-License-Identifier: BSD-3-Clause
// The Auto compositing mode's choice per frame between APC's moments and the exact segment
// baseline, from what the previous frames measured. Every input is the result of a
// collective, so every process holds the same history and takes the same decision without
// another message.
//
// The cost compared is the bytes all processes put on the wire in a frame:
// - moments: every process ships the union of covered pixels (exponent byte, moment codes,
//   colour sums), to all processes and to the display process;
// - segments: the segments that leave their process ((N-1)/N of them with direct send to
//   the strip owners) and the strips' final colours gathered on the display process.
// The segment count is estimated between segment frames as (runs per covering process) x
// (pixels each process covers, summed over processes): the first factor depends on how jagged
// the pieces are along the rays and changes little with the camera, the second is counted in
// every frame. Hysteresis keeps the mode (and so the picture: exact or approximate) from
// flickering when the costs are close.
#ifndef apcAutoMode_h
#define apcAutoMode_h

namespace apc
{

class AutoMode
{
public:
  enum Choice
  {
    Moments,
    Segments
  };

  // Bytes of one segment and of one final colour on the wire (vtkAPCCompositePass).
  static constexpr double kSegmentBytes = 24;
  static constexpr double kColourBytes = 16;
  // Switch only when the other mode is estimated this much cheaper.
  static constexpr double kHysteresis = 0.8;

  // A frame's measurements: pixels covered by some process, and covered by each process
  // summed over processes; segments only when the frame composited segments (else < 0).
  void Record(double coveredUnion, double coveredSum, double segments);

  // The mode for the next frame of `processes` processes whose moment wire costs
  // bytesPerMomentPixel per covered pixel. The first frame composites segments: it gives the
  // exact picture and measures the runs per covering process.
  Choice Choose(int processes, double bytesPerMomentPixel);

  double EstimatedMomentBytes(int processes, double bytesPerMomentPixel) const;
  double EstimatedSegmentBytes(int processes) const;
  bool HasEstimate() const { return this->RunsPerCoveringProcess > 0; }

private:
  double CoveredUnion = 0;
  double CoveredSum = 0;
  double RunsPerCoveringProcess = 0; // 0: no segment frame measured yet
  Choice Current = Segments;
};

//------------------------------------------------------------------------------
inline void AutoMode::Record(double coveredUnion, double coveredSum, double segments)
{
  this->CoveredUnion = coveredUnion;
  this->CoveredSum = coveredSum;
  if (segments >= 0 && coveredSum > 0)
  {
    this->RunsPerCoveringProcess = segments / coveredSum;
  }
}

inline double AutoMode::EstimatedMomentBytes(int processes, double bytesPerMomentPixel) const
{
  return processes > 1 ? processes * bytesPerMomentPixel * this->CoveredUnion : 0.0;
}

inline double AutoMode::EstimatedSegmentBytes(int processes) const
{
  if (processes < 2)
  {
    return 0.0;
  }
  const double leaving = (processes - 1.0) / processes;
  return leaving *
    (kSegmentBytes * this->RunsPerCoveringProcess * this->CoveredSum +
      kColourBytes * this->CoveredUnion);
}

inline AutoMode::Choice AutoMode::Choose(int processes, double bytesPerMomentPixel)
{
  if (!this->HasEstimate())
  {
    this->Current = Segments;
    return this->Current;
  }
  const double moments = this->EstimatedMomentBytes(processes, bytesPerMomentPixel);
  const double segments = this->EstimatedSegmentBytes(processes);
  if (this->Current == Segments && moments < kHysteresis * segments)
  {
    this->Current = Moments;
  }
  else if (this->Current == Moments && segments < kHysteresis * moments)
  {
    this->Current = Segments;
  }
  return this->Current;
}

} // namespace apc

#endif
