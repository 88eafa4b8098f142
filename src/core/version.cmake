# Writes version.cpp with the project version and the git commit of the
# source tree (rewritten only when it changes, so builds stay incremental).
execute_process(COMMAND git -C ${SRC} describe --always --dirty --abbrev=12
                OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT commit)
  set(commit "unknown")
endif()
set(text "namespace gradus {\nconst char *GradusVersion() { return \"${VERSION}\"; }\nconst char *GradusGitCommit() { return \"${commit}\"; }\n}  // namespace gradus\n")
if(EXISTS ${OUT})
  file(READ ${OUT} old)
endif()
if(NOT "${old}" STREQUAL "${text}")
  file(WRITE ${OUT} "${text}")
endif()
