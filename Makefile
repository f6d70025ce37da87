# Two commands for a new user (README): `make run` and `make test`.
# Both create .venv when missing and install the package into it; both are idempotent.
PY      ?= python3.11
VENV    := .venv
BIN     := $(VENV)/bin
STAMP   := $(VENV)/.installed

.PHONY: run test bench clean

$(BIN)/python:
	@command -v $(PY) >/dev/null 2>&1 || { echo "hairjax needs Python 3.11 ($(PY) not found)"; exit 1; }
	$(PY) -m venv $(VENV)

# Reinstall only when the package metadata changes.
$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	$(BIN)/python -m ipykernel install --user --name hairjax --display-name "hairjax (.venv)" >/dev/null
	touch $(STAMP)

run: $(STAMP)
	$(BIN)/hairjax render -o out/default.exr --png out/default.png --profile

test: $(STAMP)
	$(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/hairjax bench

clean:
	rm -rf out .pytest_cache
