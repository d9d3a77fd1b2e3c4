# cmake -Din=FILE -Dout=FILE -Dfrom=TEXT -Dto=TEXT -P edit_file.cmake: writes `out`, the text of `in`
# with every `from` replaced by `to` (the CLI tests derive malformed or older files from good ones)
file(READ "${in}" text)
string(FIND "${text}" "${from}" at)
if(at EQUAL -1)
  message(FATAL_ERROR "${in} does not contain '${from}'")
endif()
string(REPLACE "${from}" "${to}" text "${text}")
file(WRITE "${out}" "${text}")
