#!/usr/bin/env bash
# Installs what metaplate needs beyond the Rust toolchain, on a fresh Debian machine. Called by README.md and
# .ci/run, so the two cannot drift apart. Idempotent: re-running it installs nothing new.
set -euo pipefail

# Debian packages. The audio driver's ALSA backend (crate `alsa`, through `alsa-sys`) links libasound and finds it
# with pkg-config; everything else builds without system libraries (serialport and hidapi without libudev).
# Chromium renders `metaplate report`'s page headless in a test (tests/report.rs), as a reader would see it. mold
# links the test binaries in CI (.ci/run; several times faster than the default linker, and CI links about 50).
debian_packages=(libasound2-dev pkg-config chromium mold)

# Python packages used by tests that cross-check our output with independent tools (pinned), installed into the
# project's own virtual environment `.venv` (never the system interpreter: Debian refuses that). Tests find it as
# `.venv/bin/python` at the workspace root, or wherever METAPLATE_PYTHON points.
python_packages=(polars==2.1.0 pyarrow==26.0.1 pyuff==2.5.8)
venv_dir="$(cd "$(dirname "$0")/.." && pwd)/.venv"

if [ ${#debian_packages[@]} -gt 0 ]; then
    missing=()
    for p in "${debian_packages[@]}"; do
        dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
    done
    if [ ${#missing[@]} -gt 0 ]; then
        sudo_cmd=""
        [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
        $sudo_cmd apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
    fi
fi

if [ ${#python_packages[@]} -gt 0 ]; then
    if [ ! -x "$venv_dir/bin/python" ]; then
        if ! python3 -m venv "$venv_dir" 2>/dev/null; then
            # Debian's own python3 keeps venv in a separate package.
            rm -rf "$venv_dir"
            sudo_cmd=""
            [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
            $sudo_cmd apt-get update -qq
            DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends python3-venv
            python3 -m venv "$venv_dir"
        fi
    fi
    "$venv_dir/bin/python" -m pip install --quiet --disable-pip-version-check "${python_packages[@]}"
fi

# The test runner: cargo-nextest runs every test binary's tests in parallel across binaries (the suite's long tests
# sit in different binaries, so `cargo test`, one binary at a time, leaves a core idle for minutes). This machine
# kind ships it; elsewhere it is built once from crates.io (a few minutes).
if ! cargo nextest --version >/dev/null 2>&1; then
    # Built as a tool, never linted as ours (.ci/run makes clippy the workspace's compiler).
    env -u RUSTC_WORKSPACE_WRAPPER -u CLIPPY_ARGS cargo install cargo-nextest --locked
fi

echo "install-deps: done"
