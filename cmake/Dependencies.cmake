# All dependencies are Debian packages; scripts/setup.sh installs them.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(OpenMP REQUIRED)
find_package(TBB REQUIRED)
find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs calib3d videoio)
find_package(yaml-cpp REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(spdlog REQUIRED)
find_package(assimp REQUIRED)
# oneDNN (Debian's libdnnl-dev): conv2d's default float32 kernels (ops/conv_backend.h).
find_package(dnnl 2 CONFIG REQUIRED)

# Debian's SuiteSparse ships no CMake config: find CHOLMOD by hand.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig REQUIRED)
add_library(weft_cholmod INTERFACE)
target_include_directories(weft_cholmod INTERFACE ${CHOLMOD_INCLUDE_DIR})
target_link_libraries(weft_cholmod INTERFACE ${CHOLMOD_LIBRARY} ${SUITESPARSE_CONFIG_LIBRARY})

if(WEFT_BUILD_TESTS)
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()
if(WEFT_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()

# MPI (Debian's OpenMPI: libopenmpi-dev, openmpi-bin) for data-parallel `weft train`
# across processes and machines (nn/process_group.h); optional: on when found.
find_package(MPI COMPONENTS CXX QUIET)
option(WEFT_WITH_MPI "Data-parallel training over MPI (on when MPI is found)" ${MPI_CXX_FOUND})
if(WEFT_WITH_MPI AND NOT MPI_CXX_FOUND)
  message(FATAL_ERROR "WEFT_WITH_MPI is on but no MPI was found (scripts/setup.sh installs libopenmpi-dev)")
endif()
message(STATUS "weft: data-parallel training over MPI: ${WEFT_WITH_MPI}")
