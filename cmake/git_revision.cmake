# Writes OUTPUT (a C++ header defining PATHCL_GIT_REVISION) from `git describe` of SOURCE_DIR, at every
# build, replacing the file only when the revision changed (so nothing rebuilds needlessly).
execute_process(COMMAND git -C ${SOURCE_DIR} describe --always --dirty --abbrev=12
  OUTPUT_VARIABLE revision OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE failed)
if(failed OR revision STREQUAL "")
  set(revision "unknown (not built from a git checkout)")
endif()
set(text "#define PATHCL_GIT_REVISION \"${revision}\"\n")
if(EXISTS ${OUTPUT})
  file(READ ${OUTPUT} old)
endif()
if(NOT old STREQUAL text)
  file(WRITE ${OUTPUT} "${text}")
endif()
