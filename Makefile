# All set-up happens here: a fresh machine needs only python3 (3.11+) and make.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test bench lint bundle clean

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

bench: $(STAMP)
	$(VENV)/bin/thermost bench

lint: $(STAMP)
	$(VENV)/bin/ruff check .

bundle: $(STAMP)
	$(VENV)/bin/thermost bundle -o out/thermost_openplc.st

clean:
	rm -rf $(VENV) out .pytest_cache
