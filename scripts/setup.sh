#!/usr/bin/env bash
# Installs weft's Debian packages if any is missing (idempotent: a no-op when all are
# present). Needs root or sudo for apt-get.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libsuitesparse-dev libtbb-dev libopencv-dev libyaml-cpp-dev
  nlohmann-json3-dev libcli11-dev libspdlog-dev libassimp-dev assimp-testmodels
  libgtest-dev libgmock-dev libbenchmark-dev
  # oneDNN: the float32 convolution kernels (ops/conv_backend.h), the ones PyTorch uses.
  # Debian's dnnl-config.cmake looks for OpenCL, which libdnnl-dev does not pull in
  # without recommends: CMake's configure fails without the ICD loader's dev package.
  libdnnl-dev ocl-icd-opencl-dev
  # An optimised BLAS for CHOLMOD's supernodal factorisation (the cloth simulator): it
  # replaces the reference libblas.so.3 through Debian's alternatives; weft calls it on
  # one thread per simulation (physics/cholmod_solver.cpp). The serial and OpenMP builds
  # are not safe for weft's parallel simulations.
  libopenblas0-pthread
  # MPI for data-parallel `weft train` over several processes or machines (optional at
  # build time: CMake's WEFT_WITH_MPI is on when it is found).
  libopenmpi-dev openmpi-bin
  # Test time only: the PyTorch parity tests (tests/nn/torch_parity_integration_test.cpp)
  # run bench/resnet_torch_parity.py with Debian's PyTorch and torchvision. weft itself
  # never needs Python.
  python3 python3-torch python3-torchvision
  # Photographs behind the subject of the synthetic studio's in-the-wild takes
  # (render.background: photos): mate-backgrounds' nature photos in
  # /usr/share/backgrounds/mate/nature (GPL-2+), read from there, never copied.
  mate-backgrounds
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=""
  if [ "$(id -u)" != 0 ]; then sudo_cmd="sudo"; fi
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
