#!/usr/bin/env bash
# Builds the no_std canary (and the kernel library) for thumbv7em-none-eabihf when that
# target can be installed, and always builds the host (x86_64 Linux) no_std canary and
# runs it. Prints which builds ran; exits non-zero if any build or the host run fails.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/.." && pwd)"
target_dir="$root/target/canary"
thumb=thumbv7em-none-eabihf
ran=()

have_thumb() {
    command -v rustup >/dev/null 2>&1 || return 1
    rustup target list --installed 2>/dev/null | grep -qx "$thumb" && return 0
    echo "canary: rustup target add $thumb"
    rustup target add "$thumb"
}

cd "$here"
if have_thumb; then
    echo "canary: building the no_std canary for $thumb"
    cargo build --release --target "$thumb" --target-dir "$target_dir"
    echo "canary: building the kernel library for $thumb"
    (cd "$root" && cargo build --lib --target "$thumb")
    ran+=("$thumb (canary + kernel lib)")
else
    echo "thumbv7em target unavailable: building the host no_std canary"
fi

host="$(rustc -vV | sed -n 's/^host: //p')"
case "$host" in
    x86_64-unknown-linux-gnu)
        echo "canary: building the host no_std canary for $host"
        cargo build --release --target "$host" --target-dir "$target_dir"
        bin="$target_dir/$host/release/hydrorattle-canary"
        echo "canary: running $bin"
        status=0
        "$bin" || status=$?
        if [ "$status" -ne 0 ]; then
            echo "canary: host run failed with exit status $status (1: a kernel call returned an error, 101: panic)" >&2
            exit 1
        fi
        ran+=("$host (canary built and run: exit 0)")
        ;;
    *)
        echo "canary: no host no_std build path for $host"
        ;;
esac

if [ "${#ran[@]}" -eq 0 ]; then
    echo "canary: nothing was built" >&2
    exit 1
fi
echo "canary: OK, ran: ${ran[*]}"
