// SPDX-License-Identifier: MIT
// Internal to io/: VTK reports errors by printing them; this turns them into text to throw.
#pragma once
#include <string>

#include <vtkNew.h>

class vtkCallbackCommand;
class vtkObject;

namespace nfield::io {

// While alive, collects the ErrorEvents of `object` (which then are not printed).
class VtkErrorCatcher {
 public:
  explicit VtkErrorCatcher(vtkObject* object);
  ~VtkErrorCatcher();
  VtkErrorCatcher(const VtkErrorCatcher&) = delete;
  VtkErrorCatcher& operator=(const VtkErrorCatcher&) = delete;

  bool failed() const { return !message_.empty(); }
  // The messages caught, without VTK's source-location prefix, joined by "; ".
  const std::string& message() const { return message_; }

 private:
  static void on_error(vtkObject*, unsigned long, void* self, void* text);
  vtkObject* object_;
  vtkNew<vtkCallbackCommand> command_;
  unsigned long tag_ = 0;
  std::string message_;
};

}  // namespace nfield::io
