# The report's resources (io/report.hpp): Debian's JavaScript libraries and the page's own files,
# embedded in nhdyn_io at build time. A missing library stops the configuration with the name of
# the Debian package that provides it.
function(nhdyn_require_js_file variable path package)
  set(${variable} "${path}" CACHE FILEPATH "Embedded in the HTML report (Debian package ${package})")
  if(NOT EXISTS "${${variable}}")
    message(FATAL_ERROR "The HTML report embeds ${${variable}}, which is missing: install the Debian package "
                        "${package} (apt-get install ${package}, or scripts/install-deps), or set ${variable} "
                        "to another copy of the file.")
  endif()
endfunction()

nhdyn_require_js_file(NHDYN_THREE_JS /usr/share/javascript/three/three.min.js libjs-three)
nhdyn_require_js_file(NHDYN_KATEX_JS /usr/share/javascript/katex/katex.min.js libjs-katex)
nhdyn_require_js_file(NHDYN_KATEX_CSS /usr/share/javascript/katex/katex.min.css libjs-katex)
nhdyn_require_js_file(NHDYN_KATEX_FONT /usr/share/javascript/katex/fonts/KaTeX_Main-Regular.woff2 fonts-katex)
get_filename_component(nhdyn_katex_fonts "${NHDYN_KATEX_FONT}" DIRECTORY)

set(nhdyn_report_dir ${CMAKE_CURRENT_LIST_DIR})
set(nhdyn_report_resources ${CMAKE_CURRENT_BINARY_DIR}/report_resources.cpp)
file(GLOB nhdyn_katex_font_files "${nhdyn_katex_fonts}/*.woff2")
add_custom_command(
  OUTPUT ${nhdyn_report_resources}
  COMMAND ${CMAKE_COMMAND} -DOUT=${nhdyn_report_resources}
          "-DTEXTS=three_js=${NHDYN_THREE_JS}|katex_js=${NHDYN_KATEX_JS}|katex_css=${NHDYN_KATEX_CSS}|report_js=${nhdyn_report_dir}/report.js|report_css=${nhdyn_report_dir}/report.css"
          -DFONTS=${nhdyn_katex_fonts} -P ${nhdyn_report_dir}/embed.cmake
  DEPENDS ${nhdyn_report_dir}/embed.cmake ${nhdyn_report_dir}/report.js ${nhdyn_report_dir}/report.css
          ${NHDYN_THREE_JS} ${NHDYN_KATEX_JS} ${NHDYN_KATEX_CSS} ${nhdyn_katex_font_files}
  COMMENT "Embedding the HTML report's JavaScript libraries and fonts"
  VERBATIM)
# Raw string literals of a megabyte are what this file is for, and KaTeX's tables hold Unicode
# bidirectional marks in strings (GCC warns about those anywhere in a source).
set_source_files_properties(${nhdyn_report_resources} PROPERTIES
                            COMPILE_OPTIONS "-Wno-overlength-strings;$<$<CXX_COMPILER_ID:GNU>:-Wno-bidi-chars>")
