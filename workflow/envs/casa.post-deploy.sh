#!/usr/bin/env bash
# Run by snakemake inside the freshly built conda env (--sdm conda), from the
# working directory of the workflow: install the casa package of this checkout.
set -euo pipefail
pip install --no-deps --editable .
