// yaml-cpp helpers the io readers and writers share (internal to
// ekf_slam_core/io): loading one document without an exception escaping,
// where a node is and what it holds (for error messages), numbers, and text
// written so that it reads back unchanged.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace ekf_slam {
namespace io_yaml {

// The single YAML document of `text` into `root` (a null node for an empty
// text). Returns an empty string, or the problem (yaml-cpp's own words for
// a syntax error; a second document, or text after the first, is one too)
// with its 1-based line in `line` (0 when it has none). Never throws, and
// never loops: yaml-cpp's LoadAll does on a stray ',' after a document.
std::string loadDocument(const std::string& text, YAML::Node* root, int* line);

// The 1-based line `node` starts on; 0 for a node without a place in a file.
int lineOf(const YAML::Node& node);

// What `node` holds, for messages: 'its text' for a scalar, [a, b] for a
// short list of scalars, else "nothing", "a list of <n>" or "a mapping".
std::string describe(const YAML::Node& node);

// A scalar whose whole text (blanks around allowed) is a number, quoted or
// not; false for anything else. Infinities and NaN are numbers here: each
// reader decides whether it accepts them.
bool scalarNumber(const YAML::Node& node, double* value);

// `text` as the value of a block mapping's key, so that yaml-cpp reads back
// exactly `text`: unchanged when it reads back as a plain scalar (a frame
// id, a file name), else double-quoted with escapes.
std::string scalarText(const std::string& text);

}  // namespace io_yaml
}  // namespace ekf_slam
