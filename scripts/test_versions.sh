#!/usr/bin/env bash
# Run the test suite on several Blender releases (bpy wheels for Python 3.11), each in its own
# virtual environment (.venv-bpy-<version>), and print one summary line per version.
#   scripts/test_versions.sh [VERSION ...]     default: 4.2.23 4.5.15 5.0.1
# The README's test command stays on 5.0.1 (./run test); this is for release checks.
set -uo pipefail
cd "$(dirname "$0")/.."
versions=("$@")
[ ${#versions[@]} -gt 0 ] || versions=(4.2.23 4.5.15 5.0.1)
python=${PYTHON:-python3.11}
command -v "$python" >/dev/null || python=python3
summary=()
for version in "${versions[@]}"; do
  venv=".venv-bpy-$version"
  if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv" || { summary+=("$version: could not create $venv"); continue; }
  fi
  # bpy pins its own numpy; the rest as in requirements.txt, minus bpy/numpy
  grep -vE '^(bpy|numpy)==' requirements.txt > "$venv/requirements.txt"
  if ! "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "bpy==$version" \
       -r "$venv/requirements.txt" >"$venv/install.log" 2>&1; then
    summary+=("$version: install failed (see $venv/install.log)")
    continue
  fi
  log="$venv/pytest.log"
  "$venv/bin/python" -m pytest tests -q -p no:cacheprovider >"$log" 2>&1
  status=$?
  summary+=("bpy $version: $(grep -aE '^[0-9]+ (passed|failed)|passed|failed' "$log" | tail -n 1) (exit $status, log $log)")
done
printf '%s\n' "${summary[@]}"
