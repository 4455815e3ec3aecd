# SPDX-License-Identifier: GPL-3.0-or-later
# Runs doxygen (cmake -P, from doc/CMakeLists.txt) and fails when it fails
# or when it wrote any warning to the log (WARN_LOGFILE of the Doxyfile),
# printing the warnings.
# Also fails when a program of examples/ has no `\example` entry in
# doc/examples.txt, or is not referenced (`\ref` or `\cgalExample`) by the
# user manual, doc/Normal_orientation.txt: Doxygen does not notice either.
#   -DDOXYGEN=... -DDOXYFILE=... -DOUTPUT_DIR=... -DWARNINGS=... -DSOURCE_DIR=...
foreach(_var DOXYGEN DOXYFILE OUTPUT_DIR WARNINGS SOURCE_DIR)
  if(NOT DEFINED ${_var})
    message(FATAL_ERROR "run_doxygen.cmake: ${_var} is not set")
  endif()
endforeach()

file(GLOB _examples RELATIVE ${SOURCE_DIR}/examples ${SOURCE_DIR}/examples/*.cpp)
file(READ ${SOURCE_DIR}/doc/examples.txt _listed)
file(READ ${SOURCE_DIR}/doc/Normal_orientation.txt _manual)
set(_missing "")
set(_unreferenced "")
foreach(_example IN LISTS _examples)
  string(FIND "${_listed}" "\\example ${_example}\n" _at)
  if(_at EQUAL -1)
    list(APPEND _missing ${_example})
  endif()
  string(FIND "${_manual}" "\\ref ${_example}" _ref)
  string(FIND "${_manual}" "\\cgalExample{${_example}}" _included)
  if(_ref EQUAL -1 AND _included EQUAL -1)
    list(APPEND _unreferenced ${_example})
  endif()
endforeach()
if(_missing)
  message(FATAL_ERROR "doc/examples.txt: no \\example entry for ${_missing}")
endif()
if(_unreferenced)
  message(FATAL_ERROR "doc/Normal_orientation.txt: ${_unreferenced} not referenced (\\ref or \\cgalExample)")
endif()

# A fresh output directory: no page of an older build survives.
file(REMOVE_RECURSE ${OUTPUT_DIR}/html)
file(MAKE_DIRECTORY ${OUTPUT_DIR})
file(REMOVE ${WARNINGS})

execute_process(COMMAND ${DOXYGEN} ${DOXYFILE} RESULT_VARIABLE _status)
if(NOT _status EQUAL 0)
  message(FATAL_ERROR "doxygen failed (status ${_status})")
endif()

set(_log "")
if(EXISTS ${WARNINGS})
  file(READ ${WARNINGS} _log)
  string(STRIP "${_log}" _log)
endif()
if(NOT _log STREQUAL "")
  string(REGEX MATCHALL "\n" _lines "\n${_log}")
  list(LENGTH _lines _count)
  message("${_log}")
  message(FATAL_ERROR "doxygen: ${_count} warning line(s), see ${WARNINGS}")
endif()
message(STATUS "Manual: ${OUTPUT_DIR}/html/index.html (no doxygen warning)")
