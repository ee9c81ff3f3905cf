# hfcdem: every target runs inside the image (docker/Dockerfile), built or reused first.
# Without a Docker engine the image is built with podman/buildah (docker/README.md).
SHELL := /bin/bash
CONTAINER := bash docker/container.sh
RANKS ?= 2
CMD ?= hfcdem info

.PHONY: help image full-image test demo reproduce run shell lint

help:
	@echo "make demo    run the main demo, results under results/"
	@echo "make reproduce  the quick reproduction report of the four papers, results/reproduce/report.html"
	@echo "make test    run the test suite serially and under mpirun -n $(RANKS)"
	@echo "make run CMD=\"...\"  run a command in the image, checkout mounted"
	@echo "make shell   open a shell in the image"
	@echo "make lint    ruff and mypy on the package"
	@echo "make image | full-image   build the dependency image | the image with hfcdem installed"

image:
	@$(CONTAINER) image

full-image:
	@$(CONTAINER) full-image

test:
	@$(CONTAINER) run bash tests/run-suite.sh $(RANKS)

demo:
	@$(CONTAINER) run mpirun -n $(RANKS) python3 demos/perforation_no2.py -o results/perforation_no2 --force
	@echo "results: results/perforation_no2/ (pressure.png, fracture.png, summary.json; fields.bp and interfaces.pvd for ParaView)"

reproduce:
	@$(CONTAINER) run mpirun -n $(RANKS) hfcdem reproduce --quick -o results/reproduce
	@echo "report: results/reproduce/report.html (report.md, results.csv, figures/); the full tier: hfcdem reproduce -o DIR"

# CMD reaches the shell through the environment, unexpanded by make, so quoting
# and $variables in it survive
run: export HFCDEM_CMD = $(value CMD)
run:
	@$(CONTAINER) run bash -c "$$HFCDEM_CMD"

shell:
	@$(CONTAINER) shell

# ruff is not packaged in Debian trixie: it runs on the host (pip install ruff), mypy in the image
lint:
	@if command -v ruff >/dev/null; then ruff check hfcdem tests demos && ruff format --check hfcdem tests demos; \
	 else echo "ruff not found on the host: pip install ruff"; exit 1; fi
	@$(CONTAINER) run mypy hfcdem
