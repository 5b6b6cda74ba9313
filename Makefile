# Entry points: `make demo` and `make test` (see README.md), and `make lint`.
# All of them set up .venv first; the package is installed editable with the ROS 2
# Jazzy wheels from PyPI, so no system ROS install is needed.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

# DDS stays on this machine; a fresh domain per run keeps parallel runs apart
# (10..99 is inside the range Fast DDS accepts). An exported ROS_DOMAIN_ID wins.
ROS_ENV := export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST ROS_STATIC_PEERS= ; \
	export ROS_DOMAIN_ID=$${ROS_DOMAIN_ID:-$$(( $$$$ % 90 + 10 ))} ;

.PHONY: venv test demo bench lint

venv: $(STAMP)

$(PY):
	$(PYTHON) -m venv $(VENV)

# Reinstall only when setup.py changes (or the venv is new).
$(STAMP): setup.py | $(PY)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[ros,test]'
	touch $@

test: venv
	@$(ROS_ENV) \
	echo "ROS_DOMAIN_ID=$$ROS_DOMAIN_ID ROS_AUTOMATIC_DISCOVERY_RANGE=$$ROS_AUTOMATIC_DISCOVERY_RANGE"; \
	$(PY) -m pytest -q $(PYTEST_ARGS)

# ruff check, ruff format --check and mypy, as configured in pyproject.toml; the tools come with the
# lint extra. Every check runs; the target fails if any of them does. One line per finding here;
# `.venv/bin/ruff check` / `.venv/bin/ruff format --diff` show them in full.
LINT_STAMP := $(VENV)/.lint-installed

$(LINT_STAMP): setup.py $(STAMP)
	$(PY) -m pip install --quiet -e '.[lint]'
	touch $@

lint: $(LINT_STAMP)
	@status=0; \
	echo "lint: ruff check"; $(PY) -m ruff check --output-format concise . || status=1; \
	echo "lint: ruff format --check"; $(PY) -m ruff format --check --output-format concise . || status=1; \
	echo "lint: mypy"; $(PY) -m mypy || status=1; \
	exit $$status

demo: venv
	@$(ROS_ENV) bash scripts/demo.sh

# The benchmark suite (docs/benchmarks.md): installs the bench extra (OMPL, matplotlib).
bench: venv
	$(PY) -m pip install --quiet -e '.[bench]'
	@$(ROS_ENV) $(PY) -m benchmarks suite --doc docs/benchmarks.md $(BENCH_ARGS)
