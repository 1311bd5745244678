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
//
// Bytes are not the whole cost: the segments march every sample (transparent ones too, and
// never stop where a ray is opaque) and sort them, APC marches twice. So once both modes have
// been timed (the seconds of a frame's compositing, summed over the processes: an agreed
// value), the choice follows the time instead: each mode's last timed seconds per covered
// pixel (summed over processes), with the same hysteresis. The first timed segment frame is
// followed by one APC frame, which times APC; untimed frames (interactive ones) keep the
// measurements they find. Without times the bytes decide, as before.
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
  // summed over processes; segments only when the frame composited segments (else < 0);
  // seconds, the frame's compositing summed over the processes, only if it was timed (else
  // < 0), and whether it composited segments (else moments).
  void Record(double coveredUnion, double coveredSum, double segments, double seconds = -1,
    bool segmentFrame = false);

  // The mode for the next frame of `processes` processes whose moment wire costs
  // bytesPerMomentPixel per covered pixel. The first frame composites segments: it gives the
  // exact picture and measures the runs per covering process.
  Choice Choose(int processes, double bytesPerMomentPixel);

  double EstimatedMomentBytes(int processes, double bytesPerMomentPixel) const;
  double EstimatedSegmentBytes(int processes) const;
  bool HasEstimate() const { return this->RunsPerCoveringProcess > 0; }
  // Seconds per covered pixel (summed over processes) of the last timed frame of a mode; 0 if
  // none was timed.
  double GetSecondsPerPixel(Choice mode) const { return this->SecondsPerPixel[mode]; }

private:
  double CoveredUnion = 0;
  double CoveredSum = 0;
  double RunsPerCoveringProcess = 0;    // 0: no segment frame measured yet
  double SecondsPerPixel[2] = { 0, 0 }; // by Choice; 0: not timed yet
  Choice Current = Segments;
};

//------------------------------------------------------------------------------
inline void AutoMode::Record(
  double coveredUnion, double coveredSum, double segments, double seconds, bool segmentFrame)
{
  this->CoveredUnion = coveredUnion;
  this->CoveredSum = coveredSum;
  if (segments >= 0 && coveredSum > 0)
  {
    this->RunsPerCoveringProcess = segments / coveredSum;
  }
  if (seconds > 0 && coveredSum > 0)
  {
    this->SecondsPerPixel[segmentFrame ? Segments : Moments] = seconds / coveredSum;
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
  double moments = this->EstimatedMomentBytes(processes, bytesPerMomentPixel);
  double segments = this->EstimatedSegmentBytes(processes);
  if (this->SecondsPerPixel[Segments] > 0)
  {
    if (this->SecondsPerPixel[Moments] <= 0)
    {
      this->Current = Moments; // segments were timed: time APC once
      return this->Current;
    }
    moments = this->SecondsPerPixel[Moments];
    segments = this->SecondsPerPixel[Segments];
  }
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
