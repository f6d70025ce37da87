# Two commands for a new user (README): `make run` and `make test`.
# Both create .venv when missing and install the package into it; both are idempotent.
PY      ?= $(shell command -v python3.11 || command -v python3)
VENV    := .venv
BIN     := $(VENV)/bin
# JAX's CUDA build on a machine with an NVIDIA GPU: `make run JAX_EXTRA=cuda` installs
# pyproject's `cuda` extra (jax[cuda12]) on top (README, "On a GPU"). Its own stamp, so
# adding it to a CPU install reinstalls; `make test` afterwards keeps it.
JAX_EXTRA ?=
ifneq ($(filter-out cuda,$(JAX_EXTRA)),)
$(error JAX_EXTRA must be cuda or empty, got '$(JAX_EXTRA)')
endif
STAMP   := $(VENV)/.installed$(if $(JAX_EXTRA),-$(JAX_EXTRA))

.PHONY: run test test-slow notebooks bench clean

$(BIN)/python:
	@$(PY) -c 'import sys; assert sys.version_info >= (3, 11), sys.version' 2>/dev/null \
		|| { echo "hairjax needs Python >= 3.11 (found: $(PY))"; exit 1; }
	$(PY) -m venv $(VENV)

# The GL renderer needs EGL and Mesa's drivers (llvmpipe without a GPU). On Debian, install
# them when missing and when we may (root, apt-get present); elsewhere say what is needed.
GL_PACKAGES := libegl1 libgl1-mesa-dri

.PHONY: system-packages
system-packages:
	@if command -v dpkg >/dev/null && ! dpkg -s $(GL_PACKAGES) >/dev/null 2>&1; then \
		if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
			echo "installing $(GL_PACKAGES) for the GL renderer"; \
			apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
				apt-get install -y -qq --no-install-recommends $(GL_PACKAGES); \
		else \
			echo "note: the GL renderer needs $(GL_PACKAGES); the JAX renderer works without"; \
		fi; \
	fi

# Reinstall only when the package metadata changes.
$(STAMP): pyproject.toml | $(BIN)/python system-packages
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,reference,usd]'  # reference: Mitsuba, usd: usd-core, so their tests run
	$(if $(JAX_EXTRA),$(BIN)/python -m pip install --quiet -e '.[$(JAX_EXTRA)]')
	$(BIN)/python -m ipykernel install --sys-prefix --name python3 >/dev/null  # the notebooks' kernelspec
	touch $(STAMP)

run: $(STAMP)
	@$(BIN)/python -c 'import jax; d = jax.devices()[0]; print(f"JAX runs on {d.platform}: {d.device_kind}")'
	$(BIN)/hairjax render -o out/default.exr --png out/default.png --profile

# Each tool on its own line, so a failure names it; all before the (long) test run.
# Notebooks too: ruff reads their code cells.
test: $(STAMP)
	$(BIN)/python -m ruff check hairjax tests experiments notebooks
	$(BIN)/python -m ruff format --check hairjax tests experiments notebooks
	$(BIN)/python -m mypy
	$(BIN)/python -m pytest -q -n 2 -m "not slow"  # both cores (pytest-xdist); under 12 minutes in all

# The slow tier (pyproject.toml's marker `slow`, README): about 5 minutes on two cores.
test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -n 2 -m slow

# Every notebook executed (about 1.5 minutes).
notebooks: $(STAMP)
	HAIRJAX_ALL_NOTEBOOKS=1 $(BIN)/python -m pytest -q -n 2 tests/test_notebooks.py

bench: $(STAMP)
	$(BIN)/hairjax bench

clean:
	rm -rf out .pytest_cache
