// SPDX-License-Identifier: MIT
#include "io/pvd.h"

#include <charconv>
#include <fstream>
#include <stdexcept>

#include <vtkNew.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLDataParser.h>

#include "io/atomic_write.h"
#include "io/vtk_errors.h"

namespace nfield::io {
namespace fs = std::filesystem;

namespace {
// The shortest text that reads back as `v`.
std::string number(double v) {
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, end);
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}
}  // namespace

void PvdCollection::add(double time, std::string file, int part) {
  entries_.push_back({time, std::move(file), part});
}

void PvdCollection::write() const {
  std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const Entry& e : entries_)
    text += "    <DataSet timestep=\"" + number(e.time) + "\" group=\"\" part=\"" +
            std::to_string(e.part) + "\" file=\"" + xml_escape(e.file) + "\"/>\n";
  text += "  </Collection>\n</VTKFile>\n";
  write_atomically(path_, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    out.close();
    if (!out) throw std::runtime_error("write error");
  });
}

PvdCollection PvdCollection::read(const fs::path& path) {
  const auto fail = [&](const std::string& why) {
    return std::runtime_error("PvdCollection::read: '" + path.string() + "': " + why);
  };
  if (!fs::is_regular_file(path)) throw fail("no such file");
  vtkNew<vtkXMLDataParser> parser;
  VtkErrorCatcher errors(parser);
  parser->SetFileName(path.c_str());
  if (!parser->Parse() || errors.failed()) throw fail("not XML: " + errors.message());
  vtkXMLDataElement* root = parser->GetRootElement();
  const char* type = root ? root->GetAttribute("type") : nullptr;
  if (!root || std::string(root->GetName()) != "VTKFile" || !type ||
      std::string(type) != "Collection")
    throw fail("not a VTKFile of type Collection");
  vtkXMLDataElement* collection = root->FindNestedElementWithName("Collection");
  if (!collection) throw fail("no <Collection> element");
  PvdCollection out(path);
  for (int i = 0; i < collection->GetNumberOfNestedElements(); ++i) {
    vtkXMLDataElement* e = collection->GetNestedElement(i);
    if (std::string(e->GetName()) != "DataSet") continue;
    const char* file = e->GetAttribute("file");
    if (!file) throw fail("a <DataSet> has no file attribute");
    double time = 0;
    int part = 0;
    e->GetScalarAttribute("timestep", time);
    e->GetScalarAttribute("part", part);
    out.add(time, file, part);
  }
  return out;
}

}  // namespace nfield::io
