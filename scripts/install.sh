#!/usr/bin/env bash
# Installs the Python package softrod into a virtual environment.
#
#   bash scripts/install.sh [VENV]          release build, installed as a wheel (users)
#   bash scripts/install.sh --dev [VENV]    dev-profile editable build with the test
#                                           tools, the optional extras softrod[rl] and
#                                           softrod[ray] (gymnasium, ray) and the test
#                                           hooks (what scripts/test.sh uses); with
#                                           SOFTROD_TEST_RLLIB=1 also RLlib and PyTorch
#                                           (requirements-rllib.txt: ~3 GB, opt-in) so
#                                           that tests/test_rllib.py runs, not skips
#
# VENV defaults to .venv/ in the repository. Needs the Rust toolchain and
# Python >= 3.10 with pip (PYTHON selects the interpreter, default python3);
# maturin and the other tools come from PyPI at the versions pinned in
# crates/softrod-py/requirements*.txt.
set -euo pipefail
cd "$(dirname "$0")/.."

dev=0
if [[ "${1:-}" == "--dev" ]]; then
    dev=1
    shift
fi
venv="${1:-.venv}"
python="${PYTHON:-python3}"
pkg=crates/softrod-py

if [[ ! -x "$venv/bin/python" ]]; then
    "$python" -m venv "$venv"
fi
venv="$(cd "$venv" && pwd)"
pip=("$venv/bin/python" -m pip --disable-pip-version-check --quiet)
if [[ $dev == 1 ]]; then
    "${pip[@]}" install -r "$pkg/requirements-dev.txt"
    if [[ "${SOFTROD_TEST_RLLIB:-0}" == 1 ]]; then
        "${pip[@]}" install -r "$pkg/requirements-rllib.txt"
    fi
    # Editable install of a dev-profile build in the workspace's target/:
    # the numeric crates cargo test just built are reused, only PyO3 and the
    # bindings compile. The test hooks (`_panic`, …) the tests call are in
    # this build only, never in the release wheel.
    VIRTUAL_ENV="$venv" "$venv/bin/maturin" develop --manifest-path "$pkg/Cargo.toml" \
        --features test-hooks
else
    "${pip[@]}" install -r "$pkg/requirements-build.txt"
    wheels="$(mktemp -d)"
    trap 'rm -rf "$wheels"' EXIT
    "$venv/bin/maturin" build --release --manifest-path "$pkg/Cargo.toml" \
        --interpreter "$venv/bin/python" --out "$wheels"
    "${pip[@]}" install --force-reinstall "$wheels"/softrod-*.whl
fi
"$venv/bin/python" -c "import softrod; print('softrod', softrod.__version__, 'installed in $venv')"
