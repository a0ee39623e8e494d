# Inbetrieb: two commands. `make run` and `make test` bootstrap everything they need.
PY_SYS ?= python3
# Python keeps the bytecode it compiles (in __pycache__, ignored by git), whatever the shell says:
# with PYTHONDONTWRITEBYTECODE every process (a service, each of its workers, a CLI call, a
# test worker) compiles all it imports from source again: seconds of a core each.
unexport PYTHONDONTWRITEBYTECODE
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
# Any change to nc_sim drops every compiled cache, so no run uses a stale kernel. The kernel
# is then compiled once, here (side by side with the UI build): not by every service and test
# worker that would otherwise start at the same time and each compile it.
NUMBA_STAMP := var/.numba-sources
$(NUMBA_STAMP): $(RUN_STAMP) $(shell find nc_sim -name '*.py')
	find nc_sim -name '*.nbi' -delete -o -name '*.nbc' -delete
	$(PY) -c "from backend.workers.warmup import warm_up; warm_up()"
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

# pytest-xdist: the tests wait on machines running in real time as well as compute, so a
# worker more than there are cores keeps both busy (each worker has its own shared service and
# browser). `loadscope`: a module's tests stay on one worker, so its module-scoped service
# starts once (`loadgroup` cannot tag pytest 9.2's node ids: it grouped nothing). The Ray tests
# run after them, alone: beside the rest they took four times as long, and the rest's browser
# tests, short of CPU, missed their frames. Each part prints its slowest tests: a run that
# took longer says where.
TEST_WORKERS ?= 3
test:
	$(MAKE) --no-print-directory -j2 lint $(DIST) $(CHROMIUM) $(NUMBA_STAMP)
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist loadscope -m 'not ray' --durations=10
	$(PY) -m pytest -q -m ray --durations=10

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

# --- The container image (deploy/Containerfile) ----------------------------------------------
# No container registry is reachable here and no container engine runs: the base is Debian
# bookworm made by mmdebstrap from Debian's packages (its python3 is 3.11, as the wheels want),
# and buildah builds on it without a daemon (chroot isolation). Elsewhere any engine builds the
# same Containerfile on the official python:3.11-slim-bookworm (docs/operations-guide.md). The
# build itself reads no network: its context holds the wheels and the HMI built here.
# IMAGE_EXTRAS=cluster makes the Ray head/node image (Ray beside the service).
.PHONY: image image-base image-context image-test image-clean
IMAGE_VERSION := $(shell sed -n 's/^version = "\(.*\)"/\1/p' pyproject.toml)
IMAGE_EXTRAS ?=
IMAGE        ?= localhost/inbetrieb:$(IMAGE_VERSION)$(if $(IMAGE_EXTRAS),-$(IMAGE_EXTRAS))
IMAGE_BASE   ?= localhost/inbetrieb-base:bookworm
IMAGE_DIR    := var/image
IMAGE_CTX    := $(IMAGE_DIR)/context
WHEELS       := $(IMAGE_DIR)/wheels-$(or $(IMAGE_EXTRAS),runtime)
BUILDAH      := /usr/bin/buildah
DEBIAN       := http://deb.debian.org/debian

/usr/bin/buildah /usr/bin/mmdebstrap &:
	$(SUDO) apt-get update -q
	$(SUDO) apt-get install -y -q --no-install-recommends buildah mmdebstrap

# The base only when buildah's storage lacks it (`make image-clean` drops it, e.g. to take
# Debian's newest security updates). Docs, manuals and translations are left out as in
# Debian's slim images; the copyright files stay.
image-base: /usr/bin/buildah /usr/bin/mmdebstrap
	@$(BUILDAH) inspect --type image $(IMAGE_BASE) >/dev/null 2>&1 || { set -e; \
	  mkdir -p $(IMAGE_DIR); rm -f $(IMAGE_DIR)/base.tar; \
	  mmdebstrap --quiet --variant=minbase \
	    --include=python3,python3-venv,ca-certificates,passwd \
	    --dpkgopt='path-exclude=/usr/share/doc/*' \
	    --dpkgopt='path-include=/usr/share/doc/*/copyright' \
	    --dpkgopt='path-exclude=/usr/share/man/*' --dpkgopt='path-exclude=/usr/share/info/*' \
	    --dpkgopt='path-exclude=/usr/share/locale/*' \
	    bookworm $(IMAGE_DIR)/base.tar "deb $(DEBIAN) bookworm main" \
	    "deb $(DEBIAN) bookworm-updates main" "deb $(DEBIAN)-security bookworm-security main"; \
	  c=$$($(BUILDAH) from scratch); \
	  $(BUILDAH) add --quiet $$c $(IMAGE_DIR)/base.tar /; \
	  $(BUILDAH) config --env PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
	    --env LANG=C.UTF-8 --cmd /bin/bash $$c; \
	  $(BUILDAH) commit --quiet --rm $$c $(IMAGE_BASE) >/dev/null; \
	  rm $(IMAGE_DIR)/base.tar; echo "base image $(IMAGE_BASE) made"; }

# The runtime dependencies' wheels as constraints.txt pins them (and IMAGE_EXTRAS'), binary
# only: fetched again only when the pins change.
$(WHEELS)/.complete: pyproject.toml constraints.txt | $(RUN_STAMP)
	rm -rf $(WHEELS) && mkdir -p $(WHEELS)
	$(PY) -c 'import sys, tomllib; p = tomllib.load(open("pyproject.toml", "rb"))["project"]; \
	  print("\n".join(p["dependencies"] + [d for e in sys.argv[1:] \
	  for d in p["optional-dependencies"][e]]))' $(IMAGE_EXTRAS) > $(WHEELS)/requirements.txt
	$(PY) -m pip wheel --quiet --disable-pip-version-check --only-binary=:all: \
	  -c constraints.txt -r $(WHEELS)/requirements.txt --wheel-dir $(WHEELS)
	touch $@

# The build context: those wheels and one of this checkout (built from a copy of its sources:
# no build/ in the tree, no numba caches in the wheel), the HMI built here, the exercises.
image-context: $(WHEELS)/.complete $(DIST)
	rm -rf $(IMAGE_CTX) $(IMAGE_DIR)/src && mkdir -p $(IMAGE_CTX)/share $(IMAGE_DIR)/src
	tar -c --exclude=__pycache__ --exclude='*.nbi' --exclude='*.nbc' \
	  pyproject.toml README.md nc_sim api backend | tar -x -C $(IMAGE_DIR)/src
	cp -al $(WHEELS) $(IMAGE_CTX)/wheelhouse
	$(VENV)/bin/uv build --quiet --native-tls --wheel --out-dir $(IMAGE_CTX)/wheelhouse \
	  $(IMAGE_DIR)/src
	cp constraints.txt $(IMAGE_CTX)/wheelhouse/
	cp -r frontend/dist $(IMAGE_CTX)/share/frontend
	cp -r exercises $(IMAGE_CTX)/share/exercises
	cp deploy/healthcheck.py $(IMAGE_CTX)/
	rm -rf $(IMAGE_DIR)/src

# The previous build of the same tag is removed once the new one has it.
image: image-base image-context
	@old=$$($(BUILDAH) images --quiet --no-trunc $(IMAGE) 2>/dev/null || true); \
	start=$$(date +%s); \
	$(BUILDAH) build --quiet --isolation chroot --format docker --layers=false \
	  --build-arg BASE=$(IMAGE_BASE) --build-arg EXTRAS=$(IMAGE_EXTRAS) \
	  --tag $(IMAGE) --file deploy/Containerfile $(IMAGE_CTX) >/dev/null && \
	new=$$($(BUILDAH) images --quiet --no-trunc $(IMAGE)) && \
	if [ -n "$$old" ] && [ "$$old" != "$$new" ]; then $(BUILDAH) rmi "$$old" >/dev/null || true; fi && \
	echo "built $(IMAGE) in $$(( $$(date +%s) - start )) s: $$($(BUILDAH) images \
	  --format '{{.Size}}' $(IMAGE)) ($(IMAGE_BASE) $$($(BUILDAH) images \
	  --format '{{.Size}}' $(IMAGE_BASE)))"

# The image's smoke test (deploy/smoke.py): the entrypoint in a working container, over
# HTTP and a websocket; always on the image just built from this tree.
image-test: image $(RUN_STAMP)
	$(PY) deploy/smoke.py --image $(IMAGE)

image-clean:
	-$(BUILDAH) rmi $(IMAGE)
	-$(BUILDAH) rmi $(IMAGE_BASE)
	rm -rf $(IMAGE_DIR)
