#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# ptview -serve in a real browser: Debian's headless Chromium, driven through
# chromedriver by tests/browser/browser_test.py (what it checks is listed
# there: the page without console errors, the live diffusion's picture and
# latency, the command line that reproduces it, orbiting, the page against
# batch ptview, turntables, the bake camera and brick maps). CTest runs it
# alone (RUN_SERIAL), so that the latency it measures is the machine's.
# Needs SSS_BIN_DIR; chromium and chromium-driver (scripts/install-deps).
# SSS_SCREENSHOT_DIR: where the page's screenshots go (default: a temporary
# folder; scripts/ptview-pictures --serve makes docs/images/ptview-serve-*.png).
set -euo pipefail

bin="${SSS_BIN_DIR:?SSS_BIN_DIR must point at the build bin folder}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
for program in chromium chromedriver python3; do
    command -v "$program" >/dev/null ||
        { echo "FAIL: $program is needed (scripts/install-deps installs chromium and chromium-driver)" >&2; exit 1; }
done
work="$(mktemp -d "${TMPDIR:-/tmp}/sss_test_ptview_serve_browser.XXXXXX")"
trap 'rm -rf "$work"' EXIT
python3 "$root/tests/browser/browser_test.py" "$bin" "$work/run" "${SSS_SCREENSHOT_DIR:-$work/screenshots}"
