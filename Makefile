# seamtrack: `make demo` and `make test` set everything up themselves on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint bench images clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/seamtrack run --out runs/demo

lint: $(STAMP)
	$(BIN)/ruff check seamtrack cad tests
	$(BIN)/ruff format --check seamtrack cad tests
	$(BIN)/mypy

test: $(STAMP) lint
	MPLBACKEND=Agg $(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/seamtrack bench all --out bench-results

clean:
	rm -rf $(VENV) runs build *.egg-info
