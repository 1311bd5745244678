// Collects the errors and warnings VTK objects send, so that a test can assert what was said
// and how often (observed messages are not printed).
#ifndef apcTestMessages_h
#define apcTestMessages_h

#include "vtkCommand.h"
#include "vtkObject.h"

#include <string>
#include <vector>

namespace apctest
{

class MessageLog : public vtkCommand
{
public:
  static MessageLog* New() { return new MessageLog; }
  void Execute(vtkObject*, unsigned long event, void* data) override
  {
    const std::string text = data ? static_cast<const char*>(data) : "";
    (event == vtkCommand::ErrorEvent ? this->Errors : this->Warnings).push_back(text);
  }
  void Watch(vtkObject* object)
  {
    object->AddObserver(vtkCommand::ErrorEvent, this);
    object->AddObserver(vtkCommand::WarningEvent, this);
  }
  static bool Mentions(const std::vector<std::string>& messages, const std::string& text)
  {
    return Count(messages, text) > 0;
  }
  static int Count(const std::vector<std::string>& messages, const std::string& text)
  {
    int count = 0;
    for (const auto& m : messages)
    {
      count += m.find(text) != std::string::npos ? 1 : 0;
    }
    return count;
  }
  std::string All() const
  {
    std::string all;
    for (const auto& m : this->Errors)
    {
      all += "[error] " + m;
    }
    for (const auto& m : this->Warnings)
    {
      all += "[warning] " + m;
    }
    return all;
  }
  void Clear()
  {
    this->Errors.clear();
    this->Warnings.clear();
  }
  std::vector<std::string> Errors;
  std::vector<std::string> Warnings;
};

} // namespace apctest

#endif
