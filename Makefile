# All set-up happens here: a fresh machine needs only python3 (3.11+) and make.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test test-newest docs bench lint bundle clean browser demo fuzz checker-mutants

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[dev]'
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/thermost run

# the suite over every core, each file on one worker in file order (some files share a running PLC whose
# state carries from test to test); against a real PLC (THERMOST_PLC) in one process, as every acceptance
# test drives that one PLC. The panel's browser tests run on their own afterwards: their stack runs
# 20 x real time and needs the CPU it asks for.
BROWSER_TESTS := tests/hmi/test_panel_browser.py
TEST_WORKERS = $(if $(THERMOST_PLC),0,auto)
test: $(STAMP) browser
	$(VENV)/bin/ruff check .
	$(VENV)/bin/pytest -q -n $(TEST_WORKERS) --dist loadfile --ignore=$(BROWSER_TESTS)
	$(VENV)/bin/pytest -q $(BROWSER_TESTS)

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

# Debian's Chromium for the panel's browser tests (`playwright install` cannot download browsers here).
# Installed with apt-get when missing and running as root; never fails the build: without it the
# browser tests are skipped and pytest prints why.
CHROMIUM := /usr/lib/chromium/chromium
browser:
	@if [ -x $(CHROMIUM)-headless-shell ] || [ -x $(CHROMIUM) ]; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "make browser: installing chromium with apt-get"; \
	  export DEBIAN_FRONTEND=noninteractive; \
	  { apt-get update -qq && apt-get install -y -qq chromium fonts-liberation >/dev/null \
	    && { apt-get install -y -qq chromium-headless-shell >/dev/null 2>&1 || true; }; } \
	  || echo "make browser: apt-get could not install chromium: the browser tests will be skipped"; \
	else echo "make browser: no Chromium and no root apt-get: the browser tests will be skipped"; fi

# The live demo: simulate (soft-PLC + TCLab twin heater, Modbus on 127.0.0.1:5020) + the panel.
demo: $(STAMP)
	@echo "panel: http://127.0.0.1:8080/  (Modbus TCP 127.0.0.1:5020; Ctrl-C stops both)"
	@$(VENV)/bin/thermost simulate < /dev/null & sim=$$!; trap 'kill $$sim 2>/dev/null' EXIT INT TERM; \
	  sleep 3; $(VENV)/bin/thermost hmi --plc 127.0.0.1:5020 --port 8080

# the hostile-client test at a million writes (the suite runs 50,000): a few minutes, prints its counts
fuzz: $(STAMP)
	THERMOST_FUZZ_WRITES=1000000 $(VENV)/bin/pytest -q -s -p no:cacheprovider tests/acceptance/test_write_fuzz.py

# seeded type errors in the library, each checked as one program: a few minutes, prints its counts
checker-mutants: $(STAMP)
	$(VENV)/bin/python tests/measure_checker_mutants.py

bench: $(STAMP)
	$(VENV)/bin/thermost bench

lint: $(STAMP)
	$(VENV)/bin/ruff check .

bundle: $(STAMP)
	$(VENV)/bin/thermost bundle -o out/thermost_openplc.st

clean:
	rm -rf $(VENV) $(NEWEST) out .pytest_cache
