"""Prints "yes" when this interpreter refuses pip installs into itself (PEP 668's EXTERNALLY-MANAGED marker, outside
a virtual environment), else "no". The Makefile then installs into a project venv instead."""

import os
import sys
import sysconfig

in_venv = sys.prefix != sys.base_prefix
marker = os.path.join(sysconfig.get_path("stdlib"), "EXTERNALLY-MANAGED")
print("yes" if not in_venv and os.path.isfile(marker) else "no")
