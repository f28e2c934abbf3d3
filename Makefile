# Everything a fresh machine needs is set up here: a virtual environment with pinned-by-range deps.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test lint bench demo browser clean docs

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

# `make run PORT=8001 HOST=0.0.0.0`: another port, or every interface (then a token is printed).
PORT ?= 8000
HOST ?= 127.0.0.1

run: $(STAMP)
	$(BIN)/linkwright serve --host $(HOST) --port $(PORT)

demo: $(STAMP)
	$(BIN)/linkwright demo --out out

# The documentation site: API reference, gallery (every example runs), CLI and family guides.
docs: $(STAMP)
	$(BIN)/sphinx-build -b html -W --keep-going docs docs/_build/html
	@echo "open docs/_build/html/index.html"

# The browser tests drive Debian's chromium (Playwright's own browser downloads are not used).
browser:
	@command -v chromium >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi; \
	  echo "installing Debian's chromium for the browser tests"; \
	  $$SUDO apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq chromium >/dev/null; }

test: $(STAMP) browser
	$(BIN)/ruff check src tests bench
	$(BIN)/mypy
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -n 2

lint: $(STAMP)
	$(BIN)/ruff check src tests bench
	$(BIN)/ruff format --check src tests bench
	$(BIN)/mypy
	$(BIN)/lint-imports

BENCH_STAMP := $(VENV)/.bench-installed

$(BENCH_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[dev,bench]'
	touch $(BENCH_STAMP)

bench: $(BENCH_STAMP)
	$(BIN)/python bench/run.py
	$(BIN)/python bench/compiled.py
	for f in geared-fivebar stephenson3 watt1; do \
		$(BIN)/python bench/descriptors.py --family $$f --curves 500000; done
	$(BIN)/python bench/forces.py
	$(BIN)/python bench/synthesis.py
	$(BIN)/python bench/atlas.py
	$(BIN)/python bench/workbench.py
	$(BIN)/python bench/load.py

clean:
	rm -rf $(VENV) out .pytest_cache docs/_build docs/generated
