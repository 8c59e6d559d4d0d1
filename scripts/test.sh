#!/usr/bin/env bash
# The whole test suite: README.md's test command and CI run it after scripts/install-deps.sh.
#
# 1. Every test binary is built, then run by cargo-nextest (tests of all binaries in parallel, 2 at a time on 2
#    cores), then the doc tests.
# 2. The cross-checks with independent tools, from the same build: polars and pyarrow read a dataset and the
#    experiment report's trials, pyuff reads our universal files (`#[ignore]`d in a plain `cargo test`: they need the
#    project's .venv, which install-deps.sh makes).
# 3. The optional polars reader (store feature `polars`): polars takes minutes to build, so it builds in its own
#    target directory at the unoptimised `ci-polars` profile while step 1's tests run (its long chain of crates
#    built one after another would otherwise leave a core idle), and its test runs last.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)

cargo nextest run --workspace --locked --no-run

polars_log=target/polars-build.log
mkdir -p target
CARGO_TARGET_DIR=target/polars cargo test -p metaplate-store --locked --profile ci-polars --features polars \
    --test tests --no-run >"$polars_log" 2>&1 &
polars_build=$!
trap 'kill "$polars_build" 2>/dev/null || true' EXIT

cargo nextest run --workspace --locked
cargo test --workspace --locked --doc
cargo nextest run --workspace --locked --run-ignored only -E 'test(/^python_readers::/) | test(/^pyuff_reads::/) | test(polars_reads_the_trials_parquet)'

if ! wait "$polars_build"; then
    cat "$polars_log" >&2
    echo "test: the polars feature did not build" >&2
    exit 1
fi
trap - EXIT
CARGO_TARGET_DIR=target/polars cargo test -p metaplate-store --locked --profile ci-polars --features polars \
    --test tests -- python_readers::

echo "test: every test passed in $(( $(date +%s) - start )) s"
