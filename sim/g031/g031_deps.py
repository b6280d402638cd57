# SPDX-License-Identifier: Apache-2.0
"""Fails a virtual-G031 test with the install advice when the interpreter
running it lacks python3-unicorn or python3-pyelftools (tools/install-deps
installs both for Debian's /usr/bin/python3)."""
import sys


def require():
    """Exits 1 with the advice if unicorn or elftools cannot be imported."""
    missing = []
    for module, package in (("unicorn", "python3-unicorn"), ("elftools", "python3-pyelftools")):
        try:
            __import__(module)
        except ImportError:
            missing.append(package)
    if missing:
        print("%s cannot import %s: run tools/install-deps (apt-get install -y %s)"
              % (sys.executable, " and ".join(missing), " ".join(missing)))
        sys.exit(1)
