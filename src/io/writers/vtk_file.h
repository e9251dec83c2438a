// Private to io/: running a VTK writer so that its failures surface as an
// IoError instead of text on stderr, and its file appears whole or not at all.
// Includes VTK headers: include it from io/*.cpp and bench/*.cpp only, never
// from a public header.
#pragma once

#include "radmesh/errors.h"

#include <vtkAlgorithm.h>
#include <vtkCommand.h>
#include <vtkErrorCode.h>
#include <vtkExecutive.h>
#include <vtkNew.h>

#include "io/writers/atomic_file.h"

#include <ostream>

#include <string>

namespace radmesh::internal {

// Collects the error messages a VTK object reports. While an object has an
// ErrorEvent observer, VTK hands its errors to the observer instead of printing
// them, which keeps the library silent as docs/architecture.md requires.
class VtkErrorCatcher : public vtkCommand {
public:
  static VtkErrorCatcher* New() { return new VtkErrorCatcher; }

  void Execute(vtkObject*, unsigned long, void* call_data) override {
    // VTK's text is "ERROR: In <source file>, line N\n<Class> (0x...): <message>\n\n";
    // keep only the first line of <message>, which is what a user can act on.
    std::string text = call_data ? static_cast<const char*>(call_data) : "unknown VTK error";
    if (const auto colon = text.find("): "); colon != std::string::npos) text.erase(0, colon + 3);
    text = text.substr(0, text.find('\n'));
    if (!message.empty()) message += "; ";
    message += text;
  }

  std::string message;  // all errors seen, in order; empty when none
};

// Runs `writer` (a vtkXMLWriter or vtkImageWriter, its output and its input
// set up) and throws IoError "<path>: <VTK's reason>" if
// VTK reports an error. `path` only names the file in the message.
template <class Writer>
void run_vtk_writer(Writer* writer, const std::string& path) {
  vtkNew<VtkErrorCatcher> errors;
  writer->AddObserver(vtkCommand::ErrorEvent, errors);
  // When an algorithm fails, its executive reports that too ("Algorithm ...
  // returned failure for request: <a dump of the request>"): caught to keep
  // stderr quiet, used only when the writer itself said nothing.
  vtkNew<VtkErrorCatcher> pipeline_errors;
  writer->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, pipeline_errors);
  writer->Write();  // returns void for image writers: success is judged below

  std::string why = errors->message;
  if (why.empty() && writer->GetErrorCode() != vtkErrorCode::NoError) {
    why = vtkErrorCode::GetStringFromErrorCode(writer->GetErrorCode());
  }
  if (why.empty()) why = pipeline_errors->message;
  writer->RemoveObservers(vtkCommand::ErrorEvent);
  writer->GetExecutive()->RemoveObservers(vtkCommand::ErrorEvent);
  if (!why.empty()) throw IoError(path + ": " + why);
}

// A VTK XML writer (Base: vtkXMLUnstructuredGridWriter, vtkXMLImageDataWriter)
// that writes into a stream it is given instead of a file it opens: VTK's
// own file stream is unchecked at its close, and on a failed write VTK's
// error path frees a pointer it never set (see CheckedFile).
template <class Base>
class StreamXmlWriter : public Base {
public:
  static StreamXmlWriter* New() {
    auto* w = new StreamXmlWriter;
    w->InitializeObjectBase();
    return w;
  }
  // For the next Write() only: VTK forgets the stream when it is done.
  void SetOutputStream(std::ostream* out) { this->Stream = out; }
};

// Runs an XML `writer` (its input connected) into a temporary file renamed
// onto `path` once whole (write_file_atomically: every write checked; a
// failure throws IoError naming `path` and leaves nothing). Not through
// memory: the writer's string and the copy it hands out would hold the file
// twice at once, at the peak of a large pixmap run.
template <class Base>
void write_xml_atomically(StreamXmlWriter<Base>* writer, const std::string& path) {
  write_file_atomically(path, [&](std::ostream& out) {
    writer->SetOutputStream(&out);
    run_vtk_writer(writer, path);
  });
}

}  // namespace radmesh::internal
