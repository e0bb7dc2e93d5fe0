#!/usr/bin/env bash
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
# The per-path block kernel objects (src/sss/diffusion/isa/block_kernels.inl)
# must define nothing but their own namespace's symbols: an inline function or
# template instance emitted there (a weak symbol) would carry AVX2/AVX-512
# instructions, and the linker may keep that copy for the whole program, which
# then dies on an older CPU.  Usage: check_isa_symbols.sh OBJECT...
set -euo pipefail
(($# > 0)) || { echo "FAIL: no objects given" >&2; exit 1; }
status=0
for obj in "$@"; do
    [[ -f "$obj" ]] || { echo "FAIL: missing $obj" >&2; status=1; continue; }
    # Defined symbols other than local ones (t, r, d, b): global or weak.
    # AddressSanitizer adds an ODR indicator (__odr_asan.<symbol>) next to
    # each global, and clang's UndefinedBehaviorSanitizer (-fsanitize=function)
    # the type information of the kernels' function types (weak objects,
    # V): instrumentation data, not code.
    bad="$(nm -C --defined-only "$obj" | awk '$2 !~ /^[trdb]$/' |
        grep -v ' sss::diffusion_detail::isa_[a-z0-9_]*::kernels$' |
        grep -v ' __odr_asan\.' |
        grep -Ev ' V typeinfo (name )?for void \(' || true)"
    if [[ -n "$bad" ]]; then
        echo "FAIL: $obj defines symbols outside its path:" >&2
        echo "$bad" >&2
        status=1
    fi
done
((status == 0)) && echo "isa objects define only their kernel tables ($# objects)"
exit $status
