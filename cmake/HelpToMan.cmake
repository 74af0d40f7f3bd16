# Turns a program's --help text into a man page, so the page and --help never disagree.
#   cmake -DPROGRAM=path -DNAME=liftd -DSECTION=8 -DVERSION=0.1.0 "-DSUMMARY=one line"
#         -DOUT=liftd.8.gz -P HelpToMan.cmake
# The whole text is the DESCRIPTION, kept as written (preformatted).
execute_process(COMMAND ${PROGRAM} --help OUTPUT_VARIABLE help RESULT_VARIABLE result)
if(NOT result EQUAL 0 OR help STREQUAL "")
  message(FATAL_ERROR "${PROGRAM} --help failed (${result})")
endif()
string(REPLACE "\\" "\\e" help "${help}")
# roff reads a line starting with . or ' as a request: make it text.
string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" help "${help}")
string(TOUPPER "${NAME}" upper)
file(WRITE ${OUT}.tmp
  ".TH ${upper} ${SECTION} \"\" \"${NAME} ${VERSION}\"\n"
  ".SH NAME\n${NAME} \\- ${SUMMARY}\n"
  ".SH DESCRIPTION\n"
  "The text of \\fB${NAME} \\-\\-help\\fR:\n.PP\n.nf\n${help}.fi\n"
  ".SH SEE ALSO\n"
  "\\fBliftd\\fR(8), \\fBliftctl\\fR(1); /usr/share/doc/liftd/operations.md, config.md\n")
execute_process(COMMAND gzip -9 -n -c ${OUT}.tmp OUTPUT_FILE ${OUT} RESULT_VARIABLE result)
file(REMOVE ${OUT}.tmp)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "gzip failed for ${OUT}")
endif()
