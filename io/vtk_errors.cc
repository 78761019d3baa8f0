// SPDX-License-Identifier: MIT
#include "io/vtk_errors.h"

#include <vtkCallbackCommand.h>
#include <vtkCommand.h>
#include <vtkObject.h>

namespace nfield::io {

VtkErrorCatcher::VtkErrorCatcher(vtkObject* object) : object_(object) {
  command_->SetCallback(&VtkErrorCatcher::on_error);
  command_->SetClientData(this);
  tag_ = object_->AddObserver(vtkCommand::ErrorEvent, command_);
}

VtkErrorCatcher::~VtkErrorCatcher() { object_->RemoveObserver(tag_); }

void VtkErrorCatcher::on_error(vtkObject*, unsigned long, void* self, void* text) {
  // VTK's text: "ERROR: In <file>, line <n>\n<Class> (<address>): <message>\n\n".
  std::string m = text ? static_cast<const char*>(text) : "unknown VTK error";
  if (m.rfind("ERROR: In ", 0) == 0)
    if (auto nl = m.find('\n'); nl != std::string::npos) m.erase(0, nl + 1);
  if (auto p = m.find("): "); p != std::string::npos && p < m.find('\n')) m.erase(0, p + 3);
  while (!m.empty() && (m.back() == '\n' || m.back() == ' ')) m.pop_back();
  auto& out = static_cast<VtkErrorCatcher*>(self)->message_;
  if (!out.empty()) out += "; ";
  out += m;
}

}  // namespace nfield::io
