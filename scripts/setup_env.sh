#!/usr/bin/env bash
# Create/refresh the project virtual environment at .venv (idempotent).
# Installs the pinned requirements (requirements.lock) and the workspace
# packages (editable, so edits take effect without reinstalling).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
PY="${ACDS_PYTHON:-python3}"
STAMP="$VENV/.acds_setup_stamp"
# Every package of the workspace (a folder of ros_ws/src with a setup.py: a new node package needs no edit here)
# and every example package of a user's own node (examples/*, issue 20 §3), each installed as a user would.
PKGS=()
for d in "$ROOT"/ros_ws/src/*/ "$ROOT"/examples/*/; do [[ -f "$d/setup.py" ]] && PKGS+=("${d%/}"); done

# The OreSat C3 flight software (a user's outside program, never patched) in an environment of its own, .venv-c3,
# pinned by requirements-c3.lock; the real-C3-in-the-loop test and `acds c3` run it from there. fastcrc goes in
# first, alone: oresat-c3 asks for fastcrc~=0.3 and the pin has to hold before the resolver meets the rest.
C3_VENV="$ROOT/.venv-c3"
C3_STAMP="$C3_VENV/.acds_setup_stamp"
c3_want=$(sha256sum "$ROOT/requirements-c3.lock" | cut -c1-16)
if [[ ! -f "$C3_STAMP" || "$(cat "$C3_STAMP")" != "$c3_want" || ! -x "$C3_VENV/bin/python" ]]; then
  echo "[setup] preparing $C3_VENV (the OreSat C3 flight software, ~40 s)" >&2
  [[ -x "$C3_VENV/bin/python" ]] || "$PY" -m venv "$C3_VENV"
  "$C3_VENV/bin/python" -m pip install --quiet --disable-pip-version-check "$(grep '^fastcrc==' "$ROOT/requirements-c3.lock")" \
    2> >(grep -v "is ignored: it is neither" >&2)
  "$C3_VENV/bin/python" -m pip install --quiet --disable-pip-version-check -r "$ROOT/requirements-c3.lock" \
    2> >(grep -v "is ignored: it is neither" >&2)
  echo "$c3_want" > "$C3_STAMP"
fi

want=$(cd "$ROOT" && cat requirements.lock ros_ws/src/*/setup.py ros_ws/src/*/setup.cfg examples/*/setup.py \
  examples/*/setup.cfg 2>/dev/null | sha256sum | cut -c1-16)
# The SIMD pin where Python starts (docs/studies.md, "Running it on a cluster"): a .pth file in the environment's
# site-packages imports acds_common, whose import sets acds_common.SIMD_PIN (unless the user set the variables),
# before any program run with this Python (a Dask scheduler or worker, pytest, a node, a user's script) imports
# numpy. Sorted after the editable installs' own .pth files (site reads them in name order), so it finds acds_common.
pin_hook() {
  local site hook line='import acds_common  # the SIMD pin before numpy (acds_common.pin_simd_kernels), by scripts/setup_env.sh'
  for site in "$VENV"/lib/python3*/site-packages; do
    hook="$site/acds_simd_pin.pth"
    [[ -f "$hook" && "$(cat "$hook")" == "$line" ]] || echo "$line" > "$hook"
  done
}
if [[ -f "$STAMP" && "$(cat "$STAMP")" == "$want" && -x "$VENV/bin/python" ]]; then
  pin_hook
  exit 0
fi
echo "[setup] preparing $VENV (first run takes ~2 min)" >&2
if [[ ! -x "$VENV/bin/python" ]]; then
  "$PY" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -r "$ROOT/requirements.lock" 2> >(grep -v "is ignored: it is neither" >&2)
args=()
for p in "${PKGS[@]}"; do args+=(-e "$p"); done
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation --use-pep517 "${args[@]}" 2> >(grep -v "is ignored: it is neither" >&2)
pin_hook
# The direct engine's compiled kernels into numba's disk cache, so no first run compiles them (issue 24).
echo "[setup] compiling the direct engine's kernels (numba, once per checkout: ~40 s)" >&2
"$VENV/bin/python" -m acds_runtime.warm_kernels
echo "$want" > "$STAMP"
echo "[setup] done" >&2
