# Inbetrieb: two commands. `make run` and `make test` bootstrap everything they need.
PY_SYS ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
RUN_STAMP := $(VENV)/.bootstrap-run
DEV_STAMP := $(VENV)/.bootstrap-dev
NPM_STAMP := frontend/node_modules/.bootstrap-npm
OPENAPI   := var/openapi.json
SCHEMA_TS := frontend/src/api/schema.d.ts
DIST      := frontend/dist/index.html
CHROMIUM  := /usr/bin/chromium
SUDO      := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
API_SRC   := $(shell find api backend -name '*.py')
UI_SRC    := $(shell find frontend/src -type f ! -name schema.d.ts) frontend/index.html frontend/docs.html \
             frontend/vite.config.ts frontend/tsconfig.json

.PHONY: run test lint bench bootstrap frontend clean

# numba caches each compiled function by its own file's time stamp only: a kernel function
# that calls one from another file (the plant's drive step) would keep the old callee's code.
# Any change to nc_sim drops every compiled cache, so no run uses a stale kernel.
NUMBA_STAMP := var/.numba-sources
$(NUMBA_STAMP): $(shell find nc_sim -name '*.py')
	find nc_sim -name '*.nbi' -delete -o -name '*.nbc' -delete
	mkdir -p var && touch $(NUMBA_STAMP)

bootstrap: $(DEV_STAMP) $(NPM_STAMP)

# Serving needs only the runtime dependencies; tests, lint and benches add the dev extras
# (Ray, Playwright, schemathesis, …). Both reinstall when the pinned dependencies change.
# uv (pinned, installed by pip into the venv) fetches and unpacks in parallel: a fresh
# install takes a fraction of pip's time. It trusts the system's certificates, as pip here.
UV := $(VENV)/bin/uv pip install --quiet --native-tls --python $(PY) -c constraints.txt
$(RUN_STAMP): pyproject.toml constraints.txt
	test -x $(PY) || $(PY_SYS) -m venv $(VENV)
	$(PY) -m pip install --quiet -c constraints.txt uv
	$(UV) -e .
	touch $(RUN_STAMP)

$(DEV_STAMP): $(RUN_STAMP)
	$(UV) -e ".[dev]"
	touch $(DEV_STAMP)

# Node packages exactly as the lock file pins them.
$(NPM_STAMP): frontend/package.json frontend/package-lock.json
	cd frontend && npm ci --no-audit --no-fund
	touch $(NPM_STAMP)

# The browser's types come from the service's OpenAPI schema (websocket messages included).
$(OPENAPI): $(RUN_STAMP) $(API_SRC)
	$(PY) -m backend.cli openapi --out $(OPENAPI)

$(SCHEMA_TS): $(OPENAPI) $(NPM_STAMP)
	cd frontend && npx openapi-typescript ../$(OPENAPI) -o src/api/schema.d.ts

$(DIST): $(SCHEMA_TS) $(UI_SRC)
	cd frontend && npx vite build --logLevel warn

frontend: $(DIST)

# Browser tests drive Debian's Chromium; install it when the machine has none.
$(CHROMIUM):
	$(SUDO) apt-get update -q
	$(SUDO) apt-get install -y -q --no-install-recommends chromium

# The Python and the Node installs run side by side (-j2), then the UI build.
run:
	$(MAKE) --no-print-directory -j2 $(RUN_STAMP) $(DIST) $(NUMBA_STAMP)
	$(PY) -m backend.cli serve --host 127.0.0.1 --port 8000

lint: $(DEV_STAMP) $(SCHEMA_TS)
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .
	$(PY) -m mypy
	$(VENV)/bin/lint-imports --no-cache
	cd frontend && npx tsc --noEmit

test:
	$(MAKE) --no-print-directory -j2 lint $(DIST) $(CHROMIUM) $(NUMBA_STAMP)
	$(PY) -m pytest -q

bench: $(DEV_STAMP) $(DIST) $(CHROMIUM) $(NUMBA_STAMP)
	$(PY) bench/kernel.py
	$(PY) bench/api.py
	$(PY) bench/telemetry.py
	$(PY) bench/ui.py
	$(PY) bench/trace.py
	$(PY) bench/class.py

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache *.egg-info frontend/node_modules \
	       frontend/dist $(SCHEMA_TS) $(OPENAPI)
