PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-slow docs bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/pip install --quiet -e '.[test,docs]'
	touch $(STAMP)

DEMO := paper-pg2-l2

demo: $(STAMP)
	$(BIN)/uqflight run campaigns/$(DEMO).yaml --force
	$(BIN)/uqflight report results/$(DEMO).h5 --out results/$(DEMO)-report
	@echo "report: $(CURDIR)/results/$(DEMO)-report/report.html"

test: $(STAMP)
	$(BIN)/pytest -q -n 2 -m "not slow"

test-slow: $(STAMP)
	$(BIN)/pytest -q -n 2 -m slow

# the site (docs/ and the campaign-key reference generated from the code) into site/; strict: a broken
# link, anchor or nav entry fails (not --quiet: it hides the warnings that strict mode counts)
docs: $(STAMP)
	$(BIN)/mkdocs build --strict
	@echo "docs: $(CURDIR)/site/index.html"

bench: $(STAMP)
	for f in benchmarks/*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) results build site *.egg-info
