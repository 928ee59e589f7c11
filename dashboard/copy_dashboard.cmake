# cmake -DPAGE=<files;...> -DUPLOT_DIR=<uplot/dist> -DDEST=<folder> -P copy_dashboard.cmake
# Copies the dashboard page and uPlot's script and style sheet into DEST (only what differs).

# Without the build's npm packages (a plain cmake build, or scripts/main.sh, which installs none)
# the page is left out with a note: everything else builds, and `rig view --web` names what is
# missing.
foreach(f uPlot.iife.min.js uPlot.min.css)
  if(NOT EXISTS "${UPLOT_DIR}/${f}")
    message(NOTICE "dashboard: the page is left out: ${UPLOT_DIR}/${f} is missing (the build's npm "
      "packages are not installed; scripts/setup.sh installs tools/npm's packages into <build>/npm, "
      "then build again)")
    return()
  endif()
  list(APPEND PAGE "${UPLOT_DIR}/${f}")
endforeach()

file(MAKE_DIRECTORY "${DEST}")
foreach(src IN LISTS PAGE)
  get_filename_component(name "${src}" NAME)
  file(COPY_FILE "${src}" "${DEST}/${name}" ONLY_IF_DIFFERENT)
endforeach()
