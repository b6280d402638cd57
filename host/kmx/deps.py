# SPDX-License-Identifier: Apache-2.0
"""Optional packages from Debian's archive (pyserial, matplotlib), found
even by an interpreter that does not see Debian's dist-packages (a pyenv or
venv python3: `apt-get install python3-serial` installs for /usr/bin/python3
only). A missing package is a MissingPackage error naming what to install."""

import importlib
import os
import sys

from .errors import MissingPackage

DEBIAN_DIST_PACKAGES = "/usr/lib/python3/dist-packages"
PIP_NAMES = {"serial": "pyserial"}  # module -> its name on PyPI, where they differ


def import_debian(module, package, why):
    """Imports `module` from this interpreter, else from Debian's
    dist-packages (appended last, so it never shadows this interpreter's own
    packages). Raises MissingPackage: "<why> need(s) ...: apt-get install <package>"."""
    try:
        return importlib.import_module(module)
    except ImportError:
        pass
    top = module.split(".")[0]
    if os.path.isdir(os.path.join(DEBIAN_DIST_PACKAGES, top)) and DEBIAN_DIST_PACKAGES not in sys.path:
        sys.path.append(DEBIAN_DIST_PACKAGES)
        try:
            return importlib.import_module(module)
        except Exception:  # a compiled package built for another interpreter fails in many ways
            pass
    raise MissingPackage("%s: apt-get install %s (and run with /usr/bin/python3), or pip install %s"
                         % (why, package, PIP_NAMES.get(module.split(".")[0], module)))
