#!/usr/bin/env bash
# The kernel on a Cortex-M4F under QEMU, and its C interface. Run from anywhere:
#   bash firmware/ci.sh
# Installs what it needs (QEMU, the Arm GNU toolchain with newlib, the thumbv7em
# target, flip-link, cbindgen), then:
#   host:   fmt, clippy and rustdoc of firmware/ and ffi/; the scene and ffi tests;
#           the cbindgen header must be fresh; the C example built with cc and run;
#   target: the firmware (one binary per method, 64 KiB of RAM; RattleStable with
#           rotation at 256 KiB) run on mps2-an386, its summary lines compared with the
#           host's; each method relinked with the smallest RAM it reported and run
#           again; a deliberately small stack must end in the HardFault report; the
#           C example built with arm-none-eabi-gcc against the thumbv7em staticlib and
#           run under QEMU, its digest compared with the host C run and the firmware.
# Prints a table of flash, RAM and instructions per step (with HYDRORATTLE_BENCH_MACHINE
# set, also appended to bench/results/m4.csv by bench/record.py); fails where a binary's
# flash is more than 1 % over its last record there (bench/flash_budget.py). Without the thumbv7em
# target (or the Debian packages) it says so and runs the host part only.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/.." && pwd)"
out="$root/target/fw-ci"
thumb=thumbv7em-none-eabihf
qemu=(qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic
      -semihosting-config enable=on,target=native -icount shift=0 -kernel)
bins=(overdamped overdamped2 rattle stable springs brownian)
mkdir -p "$out"

say() { printf '\n==> %s\n' "$*"; }
run() {
    say "$*"
    "$@"
}
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi

# --- Tools ----------------------------------------------------------------------------

# HYDRORATTLE_FW_HOST_ONLY=1 runs the host part alone (as when the target is missing).
target_ok=1
if [ "${HYDRORATTLE_FW_HOST_ONLY:-0}" = 1 ]; then
    target_ok=0
elif ! command -v rustup >/dev/null 2>&1; then
    target_ok=0
elif ! rustup target list --installed 2>/dev/null | grep -qx "$thumb"; then
    rustup target add "$thumb" || target_ok=0
fi
if [ "$target_ok" -eq 1 ] && { ! command -v qemu-system-arm >/dev/null 2>&1 ||
    ! command -v arm-none-eabi-gcc >/dev/null 2>&1 || [ ! -d /usr/lib/arm-none-eabi/newlib ]; }; then
    { $sudo apt-get update -qq &&
        $sudo apt-get install -y -qq qemu-system-arm gcc-arm-none-eabi libnewlib-arm-none-eabi; } ||
        target_ok=0
fi
for tool in cbindgen flip-link; do
    if [ "$tool" = flip-link ] && [ "$target_ok" -eq 0 ]; then continue; fi
    if ! command -v "$tool" >/dev/null 2>&1; then
        run cargo install "$tool" --locked || { [ "$tool" = flip-link ] && target_ok=0; }
    fi
done
if [ "$target_ok" -eq 0 ]; then
    say "$thumb target or its tools unavailable: running the host part only"
fi

# --- Host -----------------------------------------------------------------------------

# The firmware's panic locations name source paths: remapped, so that its flash does not
# depend on where the repository or cargo's registry sits on the machine that builds it.
cargo_home="${CARGO_HOME:-$HOME/.cargo}"
remap="--remap-path-prefix=$root=/hydrorattle --remap-path-prefix=$cargo_home=/cargo"
fw() {
    (cd "$here" && CARGO_TARGET_DIR="$root/target/${FW_DIR:-fw}" \
        CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUSTFLAGS="$remap" "$@")
}
ffi() { (cd "$root/ffi" && CARGO_TARGET_DIR="$root/target/ffi" "$@"); }

run fw cargo fmt -p hydrorattle-firmware -p hydrorattle-scene -- --check
run ffi cargo fmt -- --check
run fw cargo clippy -p hydrorattle-scene --all-targets --features alloc -- -D warnings
run ffi cargo clippy --all-targets -- -D warnings
run fw env RUSTDOCFLAGS="-D warnings" cargo doc -p hydrorattle-scene --no-deps
run ffi env RUSTDOCFLAGS="-D warnings" cargo doc --no-deps
run fw cargo test -p hydrorattle-scene --release
run ffi cargo test --release

say "the checked-in header must match cbindgen's output"
ffi cbindgen --config cbindgen.toml --crate hydrorattle-ffi --output "$out/hydrorattle.h" 2>/dev/null
if ! diff -u "$root/ffi/include/hydrorattle.h" "$out/hydrorattle.h"; then
    echo "ffi/include/hydrorattle.h is stale: regenerate it (see ffi/cbindgen.toml)" >&2
    exit 1
fi

cflags=(-std=c99 -O2 -ffp-contract=off -Wall -Wextra -Werror -I"$root/ffi/include")
run ffi cargo build --release --lib
libs=$(ffi cargo rustc -q --release --lib --crate-type staticlib -- --print native-static-libs 2>&1 |
    sed -n 's/.*native-static-libs: //p' | tail -1)
# shellcheck disable=SC2086 # the library list is words
run cc "${cflags[@]}" "$root/ffi/examples/chain.c" "$root/target/ffi/release/libhydrorattle_ffi.a" \
    $libs -o "$out/chain-host"
"$out/chain-host" | tee "$out/c-host.txt"
fw cargo run -q --release -p hydrorattle-scene --features alloc --example digest >"$out/host.txt"

if [ "$target_ok" -eq 0 ]; then
    say "host part passed ($thumb part skipped)"
    exit 0
fi

# --- Target ---------------------------------------------------------------------------

# Builds binary $1 with $2 of RAM into target/$3 and runs it under QEMU; output in $4.
build_run() {
    local bin=$1 ram=$2 dir=$3 log=$4
    FW_DIR=$dir HYDRORATTLE_FW_RAM=$ram fw cargo build -q --release --target "$thumb" --bin "$bin"
    local status=0
    timeout 600 "${qemu[@]}" "$root/target/$dir/$thumb/release/$bin" >"$log" 2>&1 || status=$?
    cat "$log"
    return "$status"
}

run fw cargo clippy -p hydrorattle-firmware --target "$thumb" -- -D warnings
: >"$out/firmware.txt"
for bin in "${bins[@]}"; do
    say "$bin: 64 KiB RAM, 256 KiB flash, under QEMU"
    build_run "$bin" 64K fw "$out/$bin.txt"
    cat "$out/$bin.txt" >>"$out/firmware.txt"
done
say "stable_rotation: does not fit 64 KiB; 256 KiB"
build_run stable_rotation 256K fw-big "$out/stable_rotation.txt"
cat "$out/stable_rotation.txt" >>"$out/firmware.txt"

say "firmware summaries against the host's"
diff -u <(sort "$out/host.txt") <(grep '^figure1c ' "$out/firmware.txt" | sort)
HYDRORATTLE_FIRMWARE_OUTPUT="$out/firmware.txt" fw cargo test -q --release -p hydrorattle-scene \
    --test scene firmware_output_matches_the_host

say "each method relinked with the smallest RAM it reported (rounded up to 1 KiB)"
for bin in "${bins[@]}" stable_rotation; do
    need=$(sed -n 's/.* ram_needed=\([0-9]*\).*/\1/p' "$out/$bin.txt")
    kib=$(((need + 1023) / 1024))
    echo "$bin: ram_needed=$need -> ${kib}K"
    build_run "$bin" "${kib}K" fw-min "$out/$bin-min.txt" >/dev/null
    grep '^figure1c ' "$out/$bin-min.txt" | diff - <(grep '^figure1c ' "$out/$bin.txt")
    echo "$kib" >"$out/$bin-min-kib"
done

say "a stack too small must fault (flip-link + MPU guard), not corrupt"
bss=$(sed -n 's/.* bss=\([0-9]*\).*/\1/p' "$out/overdamped.txt")
peak=$(sed -n 's/.* stack_peak=\([0-9]*\).*/\1/p' "$out/overdamped.txt")
data=$(sed -n 's/.* data=\([0-9]*\).*/\1/p' "$out/overdamped.txt")
# The largest whole KiB of RAM that leaves the stack less than its measured peak (the
# statics, .bss and .data, come first: with the symmetric mobility's smaller .bss the
# KiB below bss + peak no longer held .data too).
small=$(((bss + data + peak - 1) / 1024))
status=0
build_run overdamped "${small}K" fw-small "$out/small-stack.txt" || status=$?
if [ "$status" -eq 0 ] || ! grep -q 'HardFault: stack overflow' "$out/small-stack.txt"; then
    echo "expected a HardFault report and a failure exit, got status $status" >&2
    exit 1
fi
echo "faulted as expected (exit status $status)"

say "C example on the Cortex-M4 (arm-none-eabi-gcc, newlib semihosting)"
run ffi cargo build --release --lib --target "$thumb"
run arm-none-eabi-gcc "${cflags[@]}" -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 \
    --specs=rdimon.specs -T "$root/ffi/examples/mps2/mps2.ld" "$root/ffi/examples/mps2/startup.c" \
    "$root/ffi/examples/chain.c" "$root/target/ffi/$thumb/release/libhydrorattle_ffi.a" -lm \
    -Wl,--gc-sections -Wl,-z,noexecstack -o "$out/chain-mps2.elf"
timeout 300 "${qemu[@]}" "$out/chain-mps2.elf" | tee "$out/c-mps2.txt"
diff -u "$out/c-host.txt" "$out/c-mps2.txt"
digest() { sed -n 's/.* digest=\([0-9a-f]*\).*/\1/p' "$1" | head -1; }
if [ "$(digest "$out/c-host.txt")" != "$(digest "$out/overdamped.txt")" ]; then
    echo "C example and Rust firmware disagree" >&2
    exit 1
fi
if [ "$(grep kT= "$out/c-host.txt" | digest /dev/stdin)" != "$(digest "$out/brownian.txt")" ]; then
    echo "C example and Rust firmware disagree on the Brownian run" >&2
    exit 1
fi

say "summary (f32, N = 25, ${#bins[@]}+1 firmware binaries; bytes)"
printf '%-16s %8s %8s %8s %8s %10s %8s %14s\n' binary flash bss stack ram_need min_ram \
    digest instr/step
# The rows of bench/results/m4.csv, one cell a line: measurement, case, quantity, value.
table="firmware per binary, f32 N = 25, 200 steps"
case_of() {
    case $1 in
    overdamped) echo Overdamped ;;
    overdamped2) echo Overdamped2 ;;
    rattle) echo Rattle ;;
    stable) echo RattleStable ;;
    springs) echo Springs ;;
    brownian) echo "Overdamped, kT = 0.5 (brownian)" ;;
    stable_rotation) echo "RattleStable, rotation" ;;
    *) echo "$1" ;;
    esac
}
: >"$out/m4-rows.tsv"
for bin in "${bins[@]}" stable_rotation; do
    dir=fw
    [ "$bin" = stable_rotation ] && dir=fw-big
    flash=$(arm-none-eabi-size -A "$root/target/$dir/$thumb/release/$bin" |
        awk '/^\.(vector_table|text|rodata) /{s+=$2} END{print s}')
    line=$(grep '^cost ' "$out/$bin.txt")
    field() { sed -n "s/.* $1=\([0-9]*\).*/\1/p" <<<"$line"; }
    printf '%-16s %8s %8s %8s %8s %9sK %8s %14s\n' "$bin" "$flash" "$(field bss)" \
        "$(field stack_peak)" "$(field ram_needed)" "$(cat "$out/$bin-min-kib")" \
        "$(digest "$out/$bin.txt" | cut -c1-8)" "$(field instructions_per_step)"
    c=$(case_of "$bin")
    printf '%s\t%s\t%s\t%s\n' "$table" "$c" flash "$flash" "$table" "$c" .bss "$(field bss)" \
        "$table" "$c" "peak stack" "$(field stack_peak)" "$table" "$c" "RAM needed" \
        "$(field ram_needed)" "$table" "$c" "min RAM" "$(cat "$out/$bin-min-kib")K" \
        "$table" "$c" "instructions / step" "$(field instructions_per_step)" \
        "$table" "$c" digest "$(digest "$out/$bin.txt")" >>"$out/m4-rows.tsv"
done
if command -v python3 >/dev/null 2>&1; then
    # Each binary's flash within 1 % of its last record, or the run fails (a deliberate
    # growth: HYDRORATTLE_FLASH_GROWTH=reason, and these rows become the budget).
    python3 "$root/bench/flash_budget.py" "$root/bench/results/m4.csv" "$out/m4-rows.tsv"
    python3 "$root/bench/record.py" --exact m4 "bash firmware/ci.sh" - <"$out/m4-rows.tsv"
fi
echo "host == Cortex-M4 bits for every binary; C example (host and QEMU) == firmware:" \
    "$(digest "$out/c-host.txt") (Brownian: $(digest "$out/brownian.txt"))"
say "firmware/ci.sh passed"
