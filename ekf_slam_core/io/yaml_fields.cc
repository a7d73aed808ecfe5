#include "ekf_slam_core/io/yaml_fields.h"

#include <yaml-cpp/eventhandler.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace ekf_slam {
namespace io_yaml {
namespace {

int lineOf(const YAML::Mark& mark) { return mark.is_null() ? 0 : mark.line + 1; }

// `value` written plain after a key, with a key after it, reads back as
// itself (no comment, flow indicator, line break or null spelling in it).
bool readsBackPlain(const std::string& value) {
  try {
    const YAML::Node root = YAML::Load("key: " + value + "\nnext: 0\n");
    return root.IsMap() && root.size() == 2 && root["key"].IsScalar() &&
           root["key"].Scalar() == value;
  } catch (const YAML::Exception&) {
    return false;
  }
}

// A parse's events, all ignored but where the last document starts.
class DocumentStarts : public YAML::EventHandler {
 public:
  YAML::Mark last = YAML::Mark::null_mark();

  void OnDocumentStart(const YAML::Mark& mark) override { last = mark; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

}  // namespace

std::string loadDocument(const std::string& text, YAML::Node* root, int* line) {
  *line = 0;
  try {
    // Not YAML::LoadAll: on text the parser cannot place after a document
    // (a stray ',' or ']') it reports an empty document without moving on,
    // and LoadAll asks again for ever, its memory growing. So the first
    // document is loaded, and the parser asked once whether another follows.
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    DocumentStarts starts;
    if (parser.HandleNextDocument(starts) && parser.HandleNextDocument(starts)) {
      *line = lineOf(starts.last);
      return "more than one YAML document (or text after the end of the first)";
    }
    *root = YAML::Load(text);
    return "";
  } catch (const YAML::Exception& e) {
    // A construct left open is found at the end of the text, which yaml-cpp
    // places on the line after a final line break: name the last line.
    const int lines = static_cast<int>(std::count(text.begin(), text.end(), '\n')) +
                      (!text.empty() && text.back() != '\n');
    *line = std::min(lineOf(e.mark), lines);
    return "not valid YAML: " + e.msg;
  }
}

int lineOf(const YAML::Node& node) { return node.IsDefined() ? lineOf(node.Mark()) : 0; }

std::string describe(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) {
    std::string items;
    for (const YAML::Node& item : node) {
      if (!item.IsScalar() || node.size() > 8) return "a list of " + std::to_string(node.size());
      items += (items.empty() ? "" : ", ") + item.Scalar();
    }
    return "[" + items + "]";
  }
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

bool scalarNumber(const YAML::Node& node, double* value) {
  if (!node.IsScalar()) return false;
  const std::string& text = node.Scalar();
  const size_t begin = text.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return false;
  const std::string number = text.substr(begin, text.find_last_not_of(" \t\r") - begin + 1);
  char* end = nullptr;
  *value = std::strtod(number.c_str(), &end);
  return end == number.c_str() + number.size();
}

std::string scalarText(const std::string& text) {
  if (readsBackPlain(text)) return text;
  std::string quoted = "\"";
  for (const char c : text) {
    const unsigned char byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      quoted += '\\';
      quoted += c;
    } else if (byte < 0x20 || byte == 0x7f) {
      char escape[8];
      std::snprintf(escape, sizeof(escape), "\\x%02x", byte);
      quoted += escape;
    } else {
      quoted += c;  // other bytes as they are: UTF-8 stays readable
    }
  }
  return quoted + "\"";
}

}  // namespace io_yaml
}  // namespace ekf_slam
