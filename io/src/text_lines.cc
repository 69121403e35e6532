#include "text_lines.h"

#include <zlib.h>

#include "skerry/core/input_error.h"

namespace skerry {

TextLines::TextLines(const std::string& path) : path_(path) {
  file_ = gzopen(path.c_str(), "rb");
  if (file_ == nullptr) throw InputError(path, 0, "", "cannot open");
}

TextLines::~TextLines() {
  if (file_ != nullptr) gzclose(static_cast<gzFile>(file_));
}

bool TextLines::Next(std::string* line) {
  gzFile f = static_cast<gzFile>(file_);
  line->clear();
  char buffer[4096];
  bool any = false;
  while (gzgets(f, buffer, sizeof(buffer)) != nullptr) {
    any = true;
    line->append(buffer);
    if (!line->empty() && line->back() == '\n') break;
  }
  int error = Z_OK;
  const char* message = gzerror(f, &error);
  if (error != Z_OK && error != Z_BUF_ERROR) {
    throw InputError(path_, line_ + 1, "", std::string("read error: ") + message);
  }
  if (!any) return false;
  ++line_;
  if (!line->empty() && line->back() == '\n') line->pop_back();
  if (!line->empty() && line->back() == '\r') line->pop_back();
  return true;
}

}  // namespace skerry
