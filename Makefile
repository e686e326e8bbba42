# seamtrack: `make demo` and `make test` set everything up themselves on a fresh machine.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint warm docs bench images clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q uv
	$(BIN)/uv pip install -q --python $(BIN)/python -e ".[dev]" || $(BIN)/pip install -q -e ".[dev]"
	touch $(STAMP)

# The paper's verification (seam mode), then the first 60 mm of its V-groove as a CAD part in
# mesh mode: Embree stripe, extractor, closed loop; and one stripe profile as a picture.
MESH_DEMO := paper-v-groove --set workpiece.params.seam_length_mm=60

demo: $(STAMP)
	$(BIN)/seamtrack run --out runs/demo --force
	$(BIN)/seamtrack run $(MESH_DEMO) --out runs/demo-mesh --force
	$(BIN)/seamtrack scan $(MESH_DEMO) --at 30 --out runs/demo-mesh/stripe.csv
	@echo "pictures: runs/demo/error.png (seam mode), runs/demo-mesh/error.png (mesh mode),"
	@echo "          runs/demo-mesh/stripe.png (the laser stripe on the CAD V-groove at 30 mm)"

lint: $(STAMP)
	$(BIN)/ruff check seamtrack cad tests
	$(BIN)/ruff format --check seamtrack cad tests
	$(BIN)/mypy

# The documentation site (docs/, mkdocs.yml) into build/site, warnings as errors: a broken
# link, a docstring griffe cannot read or a gallery example that raises fails it. The gallery's
# examples (docs/examples/) run on every build. `make test` builds it after the tests, whose
# runs have compiled the numba kernels the examples use (a fresh checkout's first build
# compiles them itself: about a minute of CPU more).
DOCS_BUILD := MPLBACKEND=Agg NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --quiet

docs: $(STAMP)
	$(DOCS_BUILD)

# The linters and `warm` side by side: `seamtrack warm` compiles the numba kernels and meshes
# the CAD parts of every built-in scene (a fresh clone's empty caches), so the suite's two
# workers load them instead of each compiling the same kernels at once (docs/speed.md).
test: $(STAMP)
	$(MAKE) --no-print-directory -j2 lint warm
	MPLBACKEND=Agg $(BIN)/python -m pytest -q -n auto
	$(DOCS_BUILD)

warm: $(STAMP)
	$(BIN)/seamtrack warm --jobs 2 --quiet

bench: $(STAMP)
	$(BIN)/seamtrack bench all --out bench-results

clean:
	rm -rf $(VENV) runs build docs/generated *.egg-info
