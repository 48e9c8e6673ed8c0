# All set-up happens here: a fresh machine needs only python3 (3.11+) and make.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test test-newest docs bench lint bundle clean

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[dev]'
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/thermost run

test: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/pytest -q

# the Modbus tests against the newest pymodbus release (pyproject pins the tested minor): a breaking
# minor release shows here the day it appears; a second venv, the pin overridden
NEWEST ?= .venv-newest
MODBUS_TESTS := tests/test_runtime_server.py tests/test_runtime_cli.py tests/test_regmap_client.py \
	tests/test_scenarios_loop.py tests/test_realtime_dead_time.py tests/test_params_cli.py tests/acceptance
test-newest: pyproject.toml
	python3 -m venv $(NEWEST)
	$(NEWEST)/bin/python -m pip install -q --upgrade pip
	$(NEWEST)/bin/python -m pip install -q -e '.[dev]'
	$(NEWEST)/bin/python -m pip install -q --upgrade pymodbus
	$(NEWEST)/bin/python -c "import pymodbus; print('pymodbus', pymodbus.__version__)"
	$(NEWEST)/bin/pytest -q $(MODBUS_TESTS)

# figures in docs/*.md between <!-- figures:NAME --> markers, and the scenario JSON Schema
docs: $(STAMP)
	$(VENV)/bin/thermost docs

bench: $(STAMP)
	$(VENV)/bin/thermost bench

lint: $(STAMP)
	$(VENV)/bin/ruff check .

bundle: $(STAMP)
	$(VENV)/bin/thermost bundle -o out/thermost_openplc.st

clean:
	rm -rf $(VENV) $(NEWEST) out .pytest_cache
