# cmake -DINPUT=file -DOUTPUT=file.cc -DSYMBOL=name -P embed_file.cmake
# Writes a C++ source defining `extern const char* const skerry_embedded_<SYMBOL>` with the text of
# INPUT, as a raw string literal. CMake expands ${content} once, so the file's own text is never
# re-evaluated.
file(READ "${INPUT}" content)
string(FIND "${content}" ")skerry_embed\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${INPUT} contains the raw-string delimiter; change it in embed_file.cmake")
endif()
# Raw string literals have an implementation limit on some compilers; split into 16 KB pieces
# that the compiler concatenates.
string(LENGTH "${content}" length)
set(pieces "")
set(offset 0)
while(offset LESS length)
  string(SUBSTRING "${content}" ${offset} 16384 piece)
  string(APPEND pieces "R\"skerry_embed(${piece})skerry_embed\"\n")
  math(EXPR offset "${offset} + 16384")
endwhile()
if(pieces STREQUAL "")
  set(pieces "\"\"")
endif()
file(WRITE "${OUTPUT}.tmp"
  "// Generated from ${INPUT} by cmake/embed_file.cmake. Do not edit.\n"
  "extern const char* const skerry_embedded_${SYMBOL};\n"
  "const char* const skerry_embedded_${SYMBOL} =\n${pieces};\n")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUTPUT}.tmp")
