#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# host/ installs as the project says (host/README.md): Debian's python3, a
# venv that sees Debian's packages, `pip install --no-build-isolation
# --no-index -e host/` (no network), then the installed `kmx` command runs
# and the package finds its register description in the checkout.
# CTest kmx_pip_install; about 10 s.
set -eu
repo=$(cd "$(dirname "$0")/../.." && pwd)
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
/usr/bin/python3 -m venv --system-site-packages "$dir/venv"
"$dir/venv/bin/pip" install -q --no-build-isolation --no-index -e "$repo/host"
cd "$dir"
"$dir/venv/bin/kmx" --help | grep -q "^usage: kmx "
"$dir/venv/bin/python" -c '
import os, sys, kmx, kmx.registers, kmx.transport
assert os.path.realpath(kmx.__file__).startswith(os.path.realpath(sys.argv[1])), kmx.__file__
print("kmx", kmx.__version__, "from", os.path.dirname(kmx.__file__), "-",
      len(kmx.registers.RegisterMap.load()), "registers; pyserial",
      kmx.transport.import_serial().VERSION)
' "$repo/host"
"$dir/venv/bin/kmx" --bus tcp:127.0.0.1:1 ping 1 2>&1 | grep -q "^kmx: tcp:127.0.0.1:1: connection refused"
echo "kmx_pip_install: ok"
