# cmake -DDIR=<generated package dir> -P LcmDecodeChecks.cmake
#
# Adds to the C++ decoders lcm-gen 1.3.1 writes the two checks they lack, so that no sequence of
# bytes makes a decoder misbehave (decoding is the first thing a rig process does with bytes from
# the network or a log; contract/decode.h):
#  - a string's encoded length must be at least 1 (its NUL): a length of 0 made the decoder call
#    std::string::assign(p, -1), which throws, and INT32_MIN made `length - 1` overflow (undefined
#    behaviour; in practice a 2 GB read past the message);
#  - a variable-length array's count must be between 0 and the bytes left (every element takes at
#    least one): the decoder resized the array to the count before reading any element, so a
#    count near 2^31 in a 200-byte message allocated tens of gigabytes.
# Each check replaces a line lcm-gen writes; a header with a string or an array whose line is not
# found fails the build (another lcm-gen version), rather than going out unchecked.
file(GLOB headers "${DIR}/*.hpp")
if(NOT headers)
  message(FATAL_ERROR "LcmDecodeChecks: no headers in ${DIR}")
endif()

# In the header text `text_var`, replaces `line` by `checked`, then fails unless the checks found
# by `check` are as many as the `sites` (the decodes the check guards) found before.
function(add_checks text_var what sites line checked check)
  set(text "${${text_var}}")
  string(REGEX MATCHALL "${sites}" found_sites "${text}")
  string(REGEX REPLACE "${line}" "${checked}" text "${text}")
  string(REGEX MATCHALL "${check}" found_checks "${text}")
  list(LENGTH found_sites n_sites)
  list(LENGTH found_checks n_checks)
  if(NOT n_sites EQUAL n_checks)
    message(FATAL_ERROR "LcmDecodeChecks: ${header}: ${n_sites} ${what} decodes, ${n_checks} checks added")
  endif()
  set(${text_var} "${text}" PARENT_SCOPE)
endfunction()

foreach(header IN LISTS headers)
  file(READ "${header}" text)
  # Strings: `if(__x_len__ > maxlen - pos) return -1;` and `if(__elem_len > maxlen - pos) return -1;`
  add_checks(text "string" "\\.assign\\("
             "if\\((__[A-Za-z0-9_]+_len__|__elem_len) > maxlen - pos\\) return -1;"
             "if(\\1 < 1 || \\1 > maxlen - pos) return -1;"
             "< 1 \\|\\| __[A-Za-z0-9_]+ > maxlen - pos")
  # Arrays: `this->x.resize(this->n);`
  add_checks(text "array" "\\.resize\\("
             "(this->[A-Za-z0-9_]+)\\.resize\\((this->[A-Za-z0-9_]+)\\);"
             "if(\\2 < 0 || \\2 > maxlen - pos) return -1;\n        \\1.resize(\\2);"
             "< 0 \\|\\| this->[A-Za-z0-9_]+ > maxlen - pos")
  file(WRITE "${header}" "${text}")
endforeach()
