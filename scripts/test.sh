#!/usr/bin/env bash
# The whole test suite: README.md's test command and CI run it after scripts/install-deps.sh.
#
# 1. Every test binary is built, then run by cargo-nextest (tests of all binaries in parallel, 2 at a time on 2
#    cores), then the doc tests. The store's optional polars reader (feature `polars`) is among them: the store's
#    own dev-dependency on itself turns the feature on in every test build.
# 2. The cross-checks with independent tools, from the same build: polars and pyarrow read a dataset and the
#    experiment report's trials, pyuff reads our universal files (`#[ignore]`d in a plain `cargo test`: they need the
#    project's .venv, which install-deps.sh makes).
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)

cargo nextest run --workspace --locked
cargo test --workspace --locked --doc
cargo nextest run --workspace --locked --run-ignored only -E 'test(/^python_readers::/) | test(/^pyuff_reads::/) | test(polars_reads_the_trials_parquet)'

echo "test: every test passed in $(( $(date +%s) - start )) s"
