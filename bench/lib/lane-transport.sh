# Sourced by per-lane transport benchmarks: lavapipe unless VK_DRIVER_FILES says
# otherwise, a work folder, and a busy loop on one core for their "noisy" setting,
# all removed on exit.
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
work=$(mktemp -d)
hog=
cleanup() { [ -n "$hog" ] && kill "$hog" 2>/dev/null; rm -rf "$work"; }
trap cleanup EXIT
# transport [ENV...] BIN: the transport's ms per iteration at 32x32x16, d = 2, taa,
# seed 7, 192 iterations, float atomics (--profile).
transport() {
  env FSOT_FLOAT_ATOMICS=1 "$@" optimize --backend vulkan --size 32x32x16 --dims 2 --kernel taa --seed 7 \
    --iterations 192 --profile --out "$work/m.exr" 2>&1 | grep -o 'transport [0-9.]* ms' | awk '{print $2}'
}
# median FILE: the median of its numbers, one a line.
median() { sort -g "$1" | awk '{a[NR]=$1} END {print (a[NR/2]+a[NR/2+1])/2}'; }
# The busy loop on core 1, started for a setting and stopped after it.
start_hog() { taskset -c 1 sh -c 'while :; do :; done' & hog=$!; }
stop_hog() { if [ -n "$hog" ]; then kill "$hog"; hog=; fi; }
