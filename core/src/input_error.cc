#include "skerry/core/input_error.h"

#include <utility>

namespace skerry {
namespace {

// `FILE:LINE: FIELD: message`; `:LINE` is left out when the line is 0 and `FIELD: ` when the
// problem is not about one field (e.g. a file that cannot be opened).
std::string FormatMessage(const std::string& file,
                          int line,
                          const std::string& field,
                          const std::string& message) {
  std::string out = file;
  if (line > 0) out += ":" + std::to_string(line);
  out += ": ";
  if (!field.empty()) out += field + ": ";
  out += message;
  return out;
}

}  // namespace

InputError::InputError(std::string file, int line, std::string field, const std::string& message)
    : std::runtime_error(FormatMessage(file, line, field, message)),
      file_(std::move(file)),
      line_(line),
      field_(std::move(field)),
      message_(message) {}

}  // namespace skerry
