#!/usr/bin/env bash
# Installs every Debian package hooke needs to build, test, run the demo and plot.
# Idempotent: installs only what is missing; a no-op (no apt-get update) when all is present.
# Run as root (or with sudo available) on Debian 12. With --paper it also installs what
# `make paper` needs (pandoc), which building and testing do not; with the argument `fuzz`, also
# the fuzzing toolchain.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev                     # dense/sparse linear algebra
  libsuitesparse-dev libmetis-dev   # CHOLMOD (no CMake config: see cmake/FindCHOLMOD.cmake)
  libopenblas-dev                   # fast BLAS for CHOLMOD (Ceres pulls ATLAS in otherwise)
  libsundials-dev                   # CVODE, IDA
  libceres-dev                      # exact implicit step as nonlinear least squares
  petsc-dev openmpi-bin             # PETSc linear backend (GAMG, hypre BoomerAMG), mpirun
  libgtest-dev libgmock-dev         # tests
  libbenchmark-dev                  # bench/
  libcli11-dev                      # the hooke command line
  libpng-dev                        # final.png pictures
  libtomlplusplus-dev               # scene files
  libspectra-dev                    # largest natural frequency (hooke info, stability limits)
  libcgal-dev                       # exact predicates: hooke check-intersections
  python3-matplotlib python3-numpy  # plots (run with /usr/bin/python3)
  python3-dev pybind11-dev          # the Python module (python/)
  python3-scipy python3-pytest      # its sparse Jacobians and its tests
  universal-ctags                   # function lengths (scripts/check-layout.py, Layout.Check)
)
if [ "${1:-}" = "--paper" ]; then
  packages+=(pandoc)                # paper/paper.md -> out/paper/paper.html
fi

# `install-deps.sh fuzz`: also clang with libFuzzer and the sanitizer runtimes (make fuzz).
if [ "${1:-}" = "fuzz" ]; then
  packages+=(clang-14 libclang-rt-14-dev)
fi
# `install-deps.sh format`: also clang-format (make format, scripts/check-format.sh).
if [ "${1:-}" = "format" ]; then
  packages+=(clang-format)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Ceres installs ATLAS beside OpenBLAS; make sure BLAS/LAPACK resolve to OpenBLAS so CHOLMOD
# does not silently run on the slower library (Debian 12's libceres-dev pulls ATLAS in).
arch=$(dpkg --print-architecture 2>/dev/null || echo amd64)
triplet=$(gcc -print-multiarch 2>/dev/null || echo x86_64-linux-gnu)
for lib in libblas.so.3 liblapack.so.3; do
  cand="/usr/lib/${triplet}/openblas-pthread/${lib}"
  if [ -e "$cand" ] && command -v update-alternatives >/dev/null; then
    cur=$(update-alternatives --query "${lib}-${triplet}" 2>/dev/null | awk '/^Value:/{print $2}')
    if [ "$cur" != "$cand" ]; then
      ${SUDO:-} update-alternatives --set "${lib}-${triplet}" "$cand" >/dev/null 2>&1 || true
    fi
  fi
done
: "$arch"
exit 0
