# cmake -DPAGE=<files;...> -DUPLOT_DIR=<uplot/dist> -DDEST=<folder> -P copy_dashboard.cmake
# Copies the dashboard page and uPlot's script and style sheet into DEST (only what differs).

foreach(f uPlot.iife.min.js uPlot.min.css)
  if(NOT EXISTS "${UPLOT_DIR}/${f}")
    message(FATAL_ERROR "dashboard: ${UPLOT_DIR}/${f} is missing: the build's npm packages "
      "are not installed; run scripts/setup.sh (it installs tools/npm's packages into "
      "<build>/npm), then build again")
  endif()
  list(APPEND PAGE "${UPLOT_DIR}/${f}")
endforeach()

file(MAKE_DIRECTORY "${DEST}")
foreach(src IN LISTS PAGE)
  get_filename_component(name "${src}" NAME)
  file(COPY_FILE "${src}" "${DEST}/${name}" ONLY_IF_DIFFERENT)
endforeach()
