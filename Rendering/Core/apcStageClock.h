// Wall-clock seconds of the stages of one frame, in the order they ran: the one clock of the
// mapper and the composite pass.
#ifndef apcStageClock_h
#define apcStageClock_h

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace apc
{

class StageClock
{
public:
  void Restart()
  {
    this->Seconds.clear();
    this->Last = std::chrono::steady_clock::now();
  }
  // Closes the stage that started at the previous lap (or restart). A stage that ran before
  // (a frame rendered band by band) adds to its first entry.
  void Lap(const std::string& stage)
  {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - this->Last).count();
    this->Last = now;
    for (auto& entry : this->Seconds)
    {
      if (entry.first == stage)
      {
        entry.second += seconds;
        return;
      }
    }
    this->Seconds.emplace_back(stage, seconds);
  }
  // The stage's seconds; null gives the total.
  double Get(const char* stage) const
  {
    double seconds = 0.0;
    for (const auto& entry : this->Seconds)
    {
      if (!stage || entry.first == stage)
      {
        seconds += entry.second;
      }
    }
    return seconds;
  }
  const std::vector<std::pair<std::string, double>>& Stages() const { return this->Seconds; }

private:
  std::vector<std::pair<std::string, double>> Seconds;
  std::chrono::steady_clock::time_point Last = std::chrono::steady_clock::now();
};

} // namespace apc

#endif
