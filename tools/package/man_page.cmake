# Writes grove(1) from the command's own help: help2man for the top level, and a COMMANDS
# section holding every subcommand's --help, found by walking the "Subcommands:" lists.
#   cmake -DGROVE=<grove> -DHELP2MAN=<help2man> -DDATA_DIR=<installed share/grove> -DOUT=<grove.1>
#         -P man_page.cmake
# DATA_DIR is what the installed command reports as its data directory (defaults in the help).
set(ENV{GROVE_DATA_DIR} "${DATA_DIR}")
set(ENV{COLUMNS} 80)

# <out>: the help of `grove <path...> --help`.
function(grove_help out)
  execute_process(COMMAND ${GROVE} ${ARGN} --help OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "grove ${ARGN} --help exited ${rc}")
  endif()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# Appends to `sections` the help of every command under `grove <path...>`, depth first.
function(grove_walk)
  grove_help(text ${ARGN})
  string(REGEX MATCH "\nSubcommands:\n.*" list "${text}")
  if(NOT list)
    string(REPLACE "\\" "\\e" text "${text}")
    string(REGEX REPLACE "\n([.'])" "\n\\\\&\\1" text "${text}")
    list(JOIN ARGN " " name)
    set(sections "${sections}.SS grove ${name}\n.nf\n${text}.fi\n" PARENT_SCOPE)
    return()
  endif()
  string(REGEX MATCHALL "\n  [a-z][a-z0-9-]*" names "${list}")
  foreach(n IN LISTS names)
    string(STRIP "${n}" n)
    grove_walk(${ARGN} ${n})
  endforeach()
  set(sections "${sections}" PARENT_SCOPE)
endfunction()

set(sections "")
grove_walk()
file(WRITE ${OUT}.include "[COMMANDS]\n${sections}
[FILES]
.TP
.I ${DATA_DIR}
The bundled data: the walk and its truth, Victoria Park, Bailey's webmap, the scenario maps
(GROVE_DATA_DIR names another directory).
")
execute_process(
  COMMAND ${HELP2MAN} --no-info --no-discard-stderr --section 1
          --name "particle-filter SLAM with shared persistent maps"
          --include ${OUT}.include --output ${OUT} ${GROVE}
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "help2man exited ${rc}")
endif()
