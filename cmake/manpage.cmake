# Writes the man page nhdyn.1 with help2man from the command's own help (cmake -P, called by the
# build: cmake/install.cmake). help2man reads `nhdyn --help` and `nhdyn --version`; the section
# COMMANDS holds every subcommand's --help (and every sub-subcommand's, as of `nhdyn study`), so
# the page lists every option the program accepts and cannot disagree with it.
#   cmake -DNHDYN=path/to/nhdyn -DHELP2MAN=help2man -DOUT=nhdyn.1 -P cmake/manpage.cmake

# The names listed under "Subcommands:" in a help text.
function(nhdyn_subcommands help out)
  string(REGEX MATCH "Subcommands:\n(.*)" section "${help}")
  set(names)
  if(section)
    string(REPLACE "\n" ";" lines "${CMAKE_MATCH_1}")
    foreach(line ${lines})
      if(line MATCHES "^  ([a-z][a-z0-9-]*)")
        list(APPEND names ${CMAKE_MATCH_1})
      endif()
    endforeach()
  endif()
  set(${out} ${names} PARENT_SCOPE)
endfunction()

# Text as roff, shown verbatim: backslashes escaped, a leading dot or quote made literal.
function(nhdyn_roff text out)
  string(REPLACE "\\" "\\e" text "${text}")
  string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

function(nhdyn_help out)
  execute_process(COMMAND ${NHDYN} ${ARGN} --help OUTPUT_VARIABLE help RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "nhdyn ${ARGN} --help exited ${rc}")
  endif()
  set(${out} "${help}" PARENT_SCOPE)
endfunction()

nhdyn_help(top)
nhdyn_subcommands("${top}" commands)
set(include "[COMMANDS]\nEvery subcommand's options, as its \\fB\\-\\-help\\fR prints them.\n")
foreach(command ${commands})
  nhdyn_help(help ${command})
  nhdyn_subcommands("${help}" subs)
  set(paths "${command}")
  foreach(sub ${subs})
    list(APPEND paths "${command}|${sub}")
  endforeach()
  foreach(path ${paths})
    string(REPLACE "|" ";" args "${path}")
    string(REPLACE "|" " " title "${path}")
    nhdyn_help(help ${args})
    nhdyn_roff("${help}" help)
    string(APPEND include ".SS \"nhdyn ${title}\"\n.nf\n${help}.fi\n")
  endforeach()
endforeach()
string(APPEND include "[SEE ALSO]\nThe documentation installed in share/doc/nhdyn (docs/cli.md: every option with examples;\n"
                      "docs/install.md), and \\fBnhdyn \\fICOMMAND\\fB \\-\\-help\\fR.\n")
get_filename_component(dir "${OUT}" DIRECTORY)
file(MAKE_DIRECTORY "${dir}")
file(WRITE "${OUT}.include" "${include}")
# help2man cannot read the version out of "nhdyn 0.2.0 (commit ...)": give it the version.
execute_process(COMMAND ${NHDYN} --version OUTPUT_VARIABLE version_line COMMAND_ERROR_IS_FATAL ANY)
string(REGEX MATCH "^nhdyn [0-9.]+" version "${version_line}")
execute_process(COMMAND ${HELP2MAN} --no-info "--version-string=${version}" --section=1
                        "--name=equations of motion of constrained mechanical systems (Do Sanh form)"
                        --include=${OUT}.include --output=${OUT} ${NHDYN}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "help2man failed (${rc})")
endif()
