# Sourced by scripts/test and scripts/demo: installs the Debian packages libdeform needs when they are missing.
# As root it runs apt-get; otherwise it prints the one `sudo apt-get install` line and stops.
deform_packages=(
  build-essential cmake pkg-config python3 clang libclang-rt-14-dev clang-format
  libglm-dev doctest-dev libopenmesh-dev nlohmann-json3-dev libbenchmark-dev
  libassimp-dev assimp-testmodels libeigen3-dev libtinygltf-dev libfast-float-dev libdragonbox-dev libmeshoptimizer-dev
  libglfw3-dev libimgui-dev libstb-dev libepoxy-dev libgl-dev libgl1-mesa-dri xvfb xauth
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib python3-pip python3-setuptools python3-wheel
  g++-mingw-w64-x86-64-posix wine wine64
  g++-aarch64-linux-gnu qemu-user
  emscripten chromium
)

deform_install_deps() {
  local missing=()
  # Node.js and npm run the peers of tests/node; a machine with its own Node.js (NodeSource's carries npm) keeps it.
  command -v npm >/dev/null || missing+=(nodejs npm)
  for p in "${deform_packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" -eq 0 ]; then
    echo "==> installing ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq && apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "libdeform needs these Debian packages; install them with:" >&2
    echo "  sudo apt-get install -y ${missing[*]}" >&2
    return 1
  fi
}

deform_jobs() { nproc 2>/dev/null || echo 2; }
