# The two set-up commands of the README: `make demo` and `make test`.
# An interpreter that refuses pip installs into itself (PEP 668: Debian 12's and Ubuntu 23.04+'s /usr/bin/python3)
# gets a project virtual environment, .venv; any other (pyenv, conda, a venv already active) is used as it is.
SYSTEM_PYTHON ?= python3
EXTERNALLY_MANAGED := $(shell $(SYSTEM_PYTHON) scripts/externally_managed.py 2>/dev/null)
ifeq ($(EXTERNALLY_MANAGED),yes)
PYTHON ?= .venv/bin/python
VENV := .venv/bin/python
else
PYTHON ?= $(SYSTEM_PYTHON)
VENV :=
endif
PIP ?= $(PYTHON) -m pip

.PHONY: system install install-test demo test bench

system:
	EVPOSE_NEED_VENV=$(EXTERNALLY_MANAGED) bash scripts/setup_system.sh

.venv/bin/python: | system
	$(SYSTEM_PYTHON) -m venv .venv

install: system $(VENV)
	$(PIP) install -q -c constraints.txt -e .

install-test: system $(VENV)
	$(PIP) install -q -c constraints.txt -e ".[test]"

demo: install
	$(PYTHON) -m evpose.cli.main app --data demo_data maps

test: install-test
	$(PYTHON) -m pytest -q -p no:cacheprovider tests

bench: install
	$(PYTHON) -m evpose.cli.main bench --suite quick --out bench_out
