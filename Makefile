# The two set-up commands of the README: `make demo` and `make test`.
PYTHON ?= python3
PIP ?= $(PYTHON) -m pip

.PHONY: install install-test demo test bench

install:
	bash scripts/setup_system.sh
	$(PIP) install -q -c constraints.txt -e .

install-test:
	bash scripts/setup_system.sh
	$(PIP) install -q -c constraints.txt -e ".[test]"

demo: install
	$(PYTHON) -m evpose.cli.main app --data demo_data maps

test: install-test
	$(PYTHON) -m pytest -q -p no:cacheprovider tests

bench: install
	$(PYTHON) -m evpose.cli.main bench --suite quick --out bench_out
