#pragma once
/// \file
/// The typed error raised for bad input (files, configuration). It names the file, the line
/// (0 when the problem is not tied to one line) and the field, and is caught at the CLI boundary.

#include <stdexcept>
#include <string>

namespace skerry {

/// InputError's `file` for an error in the command's own arguments (the field names the option).
inline constexpr char kCommandLine[] = "(command line)";

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, int line, std::string field, const std::string& message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& field() const { return field_; }
  /// What is wrong, without the file, line and field.
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  std::string field_;
  std::string message_;
};

}  // namespace skerry
