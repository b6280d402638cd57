#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# host/ installs as host/README.md says, without network:
#  1. Debian's python3, a venv that sees Debian's packages (pyserial, the
#     declared dependency, is python3-serial), `pip install
#     --no-build-isolation --no-index host/` (a real install, not -e): from
#     another directory the installed kmx runs and reads registers.json and
#     products.json from its own site-packages (importlib.resources), not
#     from the checkout;
#  2. the same editable (-e), the package then being the checkout's;
#  3. the python3 on PATH when it is another interpreter (pyenv's): a venv
#     without Debian's packages; with setuptools and wheel there, `--no-deps`
#     (pyserial cannot come from the network); without wheel (pip cannot
#     build offline) `PYTHONPATH=host python -m kmx`: either way kmx finds
#     Debian's pyserial itself (kmx/deps.py) and runs.
# CTest kmx_pip_install; about 60 s on a loaded machine.
set -eu
unset PYTHONPATH  # CTest puts host/ on it for every test; an installed kmx must be found without it
repo=$(cd "$(dirname "$0")/../.." && pwd)
dir=$(mktemp -d)
trap 'rm -rf "$dir" "$repo/host/build" "$repo/host/kmx.egg-info"' EXIT
check='
import os, sys, kmx, kmx.registers, kmx.transport, kmx.products
where = os.path.realpath(os.path.dirname(kmx.__file__))
regs = kmx.registers.RegisterMap.load()
want = sys.argv[1]
assert where.startswith(os.path.realpath(want)), (where, want)
assert os.path.abspath(regs.source).startswith(os.path.abspath(want)), regs.source
assert kmx.products.load_products()["products"]["KM-SIM-P135"]["current_max_ma"] == 3000
print("kmx", kmx.__version__, "from", where, "-", len(regs), "registers from", regs.source,
      "; pyserial", kmx.transport.import_serial().VERSION)
'
run_kmx() {  # the installed kmx command answers and opens a transport
    "$1/bin/kmx" --help | grep -q "^usage: kmx "
    "$1/bin/kmx" --bus tcp:127.0.0.1:1 ping 1 2>&1 | grep -q "^kmx: tcp:127.0.0.1:1: connection refused"
}

/usr/bin/python3 -m venv --system-site-packages "$dir/deb"
"$dir/deb/bin/pip" install -q --no-build-isolation --no-index "$repo/host"
"$dir/deb/bin/pip" show kmx | grep -q "^Requires: pyserial"
site=$("$dir/deb/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
(cd "$dir" && "$dir/deb/bin/python" -c "$check" "$site")
(cd "$dir" && run_kmx "$dir/deb")

/usr/bin/python3 -m venv --system-site-packages "$dir/edit"
"$dir/edit/bin/pip" install -q --no-build-isolation --no-index -e "$repo/host"
(cd "$dir" && "$dir/edit/bin/python" -c "$check" "$repo/host")
(cd "$dir" && run_kmx "$dir/edit")

other=$(command -v python3 || true)
if [ -n "$other" ] && [ "$(realpath "$other")" != "$(realpath /usr/bin/python3)" ] \
   && "$other" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
    "$other" -m venv "$dir/other"
    if "$dir/other/bin/python" -c 'import setuptools, wheel' 2>/dev/null; then
        "$dir/other/bin/pip" install -q --no-build-isolation --no-index --no-deps "$repo/host"
        site=$("$dir/other/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
        (cd "$dir" && "$dir/other/bin/python" -c "$check" "$site")
        (cd "$dir" && run_kmx "$dir/other")
        echo "kmx_pip_install: $other venv: installed, ok"
    else
        # no wheel package in that venv and no network to fetch it: pip cannot
        # build; host/README.md's one line says so, and kmx runs from the checkout
        (cd "$dir" && PYTHONPATH="$repo/host" "$dir/other/bin/python" -c "$check" "$repo/host")
        (cd "$dir" && PYTHONPATH="$repo/host" "$dir/other/bin/python" -m kmx --bus tcp:127.0.0.1:1 ping 1 2>&1 \
            | grep -q "^kmx: tcp:127.0.0.1:1: connection refused")
        echo "kmx_pip_install: $other venv without wheel: runs as PYTHONPATH=host python -m kmx, ok"
    fi
fi
echo "kmx_pip_install: ok"
