#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Checks the plant against the Cortex-M0 bar: it must compile for the M0 with
# the project's warnings as errors, use no floating point (no soft-float
# helpers), no heap, and no 64-bit division outside km_plant_init (64-bit
# divides are slow libgcc calls on the M0; the step runs every control tick).
# Usage: check_m0.sh CC SOURCE_DIR
set -eu
cc=$1
src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
status=0
for f in "$src"/*.c; do
    o="$tmp/$(basename "$f").o"
    "$cc" -std=c11 -mcpu=cortex-m0 -mthumb -Os -ffunction-sections \
        -Wall -Wextra -Wconversion -Wshadow -Werror -I"$src" -c "$f" -o "$o"
    undefined=$("${cc%gcc}nm" -u "$o" | awk '{print $NF}')
    for sym in $undefined; do
        case $sym in
        __aeabi_[fd]*|__aeabi_*2f|__aeabi_*2d|__aeabi_*2fz|__aeabi_*2dz|*malloc|*free|*calloc|*realloc)
            echo "$f: uses $sym (float or heap)"; status=1 ;;
        esac
    done
    # 64-bit division, allowed only in the init-time sections
    "${cc%gcc}objdump" -r "$o" | awk -v f="$f" '
        /^RELOCATION RECORDS FOR/ { sec = $4 }
        /__aeabi_(u)?ldivmod/ && sec !~ /km_plant_init/ { print f ": 64-bit division in " sec; bad = 1 }
        END { exit bad }' || status=1
done
[ $status -eq 0 ] && echo "plant: M0 build clean, no float, no heap, no 64-bit divide in the step"
exit $status
