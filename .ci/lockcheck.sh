#!/usr/bin/env bash
# Fails when the lock files disagree on a version. The workspace, python/, ffi/,
# firmware/ and canary/ each resolve their own dependencies (each is its own cargo
# workspace: targets, profiles and panic strategies differ), but the kernel must compute
# the same bits in every one of them, so every package they share must resolve to the
# same version everywhere. Run from anywhere:
#   bash .ci/lockcheck.sh              # every Cargo.lock git tracks
#   bash .ci/lockcheck.sh A.lock B.lock ...
# Packages are compared within one semver-compatible range (syn 2.x and syn 3.x may
# both be present; syn 3.0.9 in one lock and 3.0.10 in another is drift). To fix a
# drift, pin the odd one out, e.g. `(cd ffi && cargo update -p glam --precise 0.34.2)`.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
if [ "$#" -gt 0 ]; then
    locks=("$@")
else
    mapfile -t locks < <(git ls-files -- 'Cargo.lock' '*/Cargo.lock')
fi
if [ "${#locks[@]}" -lt 2 ]; then
    echo "lockcheck: fewer than two lock files (${locks[*]:-none}): nothing to compare" >&2
    exit 1
fi

# One line per (lock, package): "name key version lock", key being the range cargo
# treats as compatible (the major version; 0.minor below 1.0; 0.0.patch below 0.1).
awk '
    FNR == 1 { name = "" }
    /^name = "/ { name = $3; gsub(/"/, "", name); next }
    /^version = "/ && name != "" {
        version = $3; gsub(/"/, "", version)
        split(version, part, /[.+-]/)
        key = part[1] > 0 ? part[1] : (part[2] > 0 ? "0." part[2] : "0.0." part[3])
        print name, key, version, FILENAME
        name = ""
    }
' "${locks[@]}" | sort | awk '
    { id = $1 " " $2 }
    id != last { if (n > 1 && drift) report(); last = id; n = 0; drift = 0; first = $3; lines = "" }
    {
        n++
        if ($3 != first) drift = 1
        lines = lines sprintf("    %-10s %s\n", $3, $4)
    }
    END { if (n > 1 && drift) report(); exit bad }
    function report() { bad = 1; split(last, w, " "); printf "drift: %s (%s) resolves differently\n%s", w[1], w[2], lines }
' || {
    echo "lockcheck: the lock files disagree (checked: ${locks[*]})" >&2
    exit 1
}
echo "lockcheck: ${#locks[@]} lock files agree on every shared package"
