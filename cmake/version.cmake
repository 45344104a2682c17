# Writes generated/kiln/version.hpp with the current git hash; run at every build so the hash in
# run output is never stale. configure_file only touches the file when its content changes.
execute_process(COMMAND git rev-parse --short=12 HEAD
  WORKING_DIRECTORY ${SOURCE_DIR} OUTPUT_VARIABLE KILN_GIT_HASH
  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
execute_process(COMMAND git status --porcelain --untracked-files=no
  WORKING_DIRECTORY ${SOURCE_DIR} OUTPUT_VARIABLE _dirty
  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT KILN_GIT_HASH)
  set(KILN_GIT_HASH "unknown")
elseif(_dirty)
  set(KILN_GIT_HASH "${KILN_GIT_HASH}-modified")
endif()
configure_file(${SOURCE_DIR}/src/core/version.hpp.in ${BINARY_DIR}/generated/kiln/version.hpp @ONLY)
