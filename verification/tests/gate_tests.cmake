# cmake -DVERIFY=liquid-verify -DREFERENCE=dir -DOUT=file -P gate_tests.cmake
# Writes one ctest `gate.<case>` per quick case that liquid-verify lists, for ctest to include.
execute_process(COMMAND ${VERIFY} list --quick-names OUTPUT_VARIABLE names RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${VERIFY} list --quick-names failed (${status})")
endif()
string(REPLACE "\n" ";" names "${names}")
# Cases whose wall times are asserted (poisson-adaptivity-gain's time gain) or are the figures a
# reader compares (ppe-solvers' seconds and SpMV-equivalents) run alone; ci/test runs the other
# gates two at a time.
set(serial poisson-adaptivity-gain ppe-solvers)
set(text "# Generated from `liquid-verify list --quick-names`; do not edit.\n")
foreach(name ${names})
  if(name STREQUAL "")
    continue()
  endif()
  string(APPEND text "add_test(gate.${name} \"${VERIFY}\" gate --case ${name} --reference \"${REFERENCE}\")\n")
  string(APPEND text "set_tests_properties(gate.${name} PROPERTIES LABELS verification)\n")
  list(FIND serial ${name} alone)
  if(NOT alone EQUAL -1)
    string(APPEND text "set_tests_properties(gate.${name} PROPERTIES RUN_SERIAL TRUE)\n")
  endif()
endforeach()
file(WRITE ${OUT}.tmp "${text}")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
