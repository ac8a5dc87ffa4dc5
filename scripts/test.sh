#!/usr/bin/env bash
# Every test of the repository: the Rust workspace, then the Python package.
#
#   bash scripts/test.sh
#
# Needs the Rust toolchain and Python >= 3.10 with pip. The Python tests run
# in .venv/ (created if missing; SOFTROD_VENV picks another), with maturin,
# numpy, pytest and cosseratbench at the versions pinned in
# crates/softrod-py/requirements-dev.txt, against a dev-profile build that
# shares target/ with cargo test. Set SOFTROD_TEST_BENCHES=1 to build the
# criterion benches too.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${SOFTROD_VENV:-.venv}"

# The 3-D view is tested in a real headless browser (crates/softrod-viz/tests/browser.rs).
if [[ -z "${SOFTROD_CHROMIUM:-}" ]] && ! command -v chromium >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1 && [[ "$(id -u)" == 0 ]]; then
        echo "== installing Debian's chromium for the browser test"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
    else
        echo "scripts/test.sh: the browser test needs chromium (apt-get install chromium, or set SOFTROD_CHROMIUM)" >&2
        exit 1
    fi
fi

# The instruction-count gate counts with valgrind's callgrind.
if ! command -v valgrind >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1 && [[ "$(id -u)" == 0 ]]; then
        echo "== installing Debian's valgrind for the instruction-count gate"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq valgrind >/dev/null
    else
        echo "scripts/test.sh: the instruction-count gate needs valgrind (apt-get install valgrind)" >&2
        exit 1
    fi
fi

echo "== Rust tests"
# The criterion benches (softrod-benches: criterion and its dependencies, the
# bench tables binary, the study examples) hold no tests: they are built
# only when asked (SOFTROD_TEST_BENCHES=1 here, or `cargo bench`); `cargo
# clippy --all-targets` in .ci/run still compiles them.
if [[ "${SOFTROD_TEST_BENCHES:-0}" == 1 ]]; then
    cargo test --workspace
else
    cargo test --workspace --exclude softrod-benches
fi

echo "== instruction-count gate (the dynamics' hot paths, callgrind; docs/performance.md)"
python3 scripts/instruction_gate.py

echo "== Python package (dev build into $venv)"
bash scripts/install.sh --dev "$venv"

echo "== Python tests"
# The CLI-equality tests run the `softrod` binary cargo test just built.
SOFTROD_BIN="$PWD/target/debug/softrod" "$venv/bin/python" -m pytest crates/softrod-py/tests -q
