# Fixture of the app CLI tests: a small tracked sequence (gen blobs, 4 frames) in SCRATCH/input, SCRATCH/tracked.
#   -DEXE=<topotrack> -DSCRATCH=<folder>
file(REMOVE_RECURSE ${SCRATCH})
foreach(step "gen;blobs;-o;${SCRATCH}/input;--frames;4;--resolution;24;--progress;quiet"
             "track;${SCRATCH}/input;-o;${SCRATCH}/tracked;--quiet")
  execute_process(COMMAND ${EXE} ${step} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 100)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "topotrack ${step} failed (${rc}):\n${out}\n${err}")
  endif()
endforeach()
