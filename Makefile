# Two commands do all set-up: `make demo` and `make test` (both create .venv/ when missing).
PYTHON ?= python3
VENV := .venv
VPY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: venv demo test bench reproduce soak clean

venv: $(STAMP)

$(STAMP): setup.py
	test -x $(VPY) || $(PYTHON) -m venv $(VENV)
	$(VPY) -m pip install --quiet --upgrade pip
	$(VPY) -m pip install --quiet -e ".[ros,test]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/ipomdp-gaze demo

test: $(STAMP)
	$(VPY) -m pytest -q test

bench: $(STAMP)
	$(VPY) bench/run.py

reproduce: $(STAMP)
	$(VENV)/bin/ipomdp-gaze reproduce

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
