# Sourced by the quick-start scripts: create .venv with Python 3.12 and install the project.
# OpenSeesPy 3.8 needs Python 3.12 (with 3.11 pip silently picks OpenSeesPy 3.7, which
# fails to import without the system BLAS).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

find_python312() {
  local candidates=(python3.12)
  if command -v pyenv >/dev/null 2>&1; then
    local v
    for v in $(pyenv versions --bare 2>/dev/null | grep -E '^3\.12(\.|$)' | sort -rV); do
      candidates+=("$(pyenv root)/versions/$v/bin/python3.12")
    done
  fi
  candidates+=(/root/.pyenv/versions/3.12*/bin/python3.12 /usr/local/bin/python3.12 /usr/bin/python3.12)
  local c
  for c in "${candidates[@]}"; do
    if "$c" -c 'import sys; assert sys.version_info[:2] == (3, 12)' >/dev/null 2>&1; then
      echo "$c"; return 0
    fi
  done
  return 1
}

if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c 'import sys; assert sys.version_info[:2] == (3, 12)' 2>/dev/null; then
  PY=$(find_python312) || { echo "error: Python 3.12 not found (OpenSeesPy 3.8 needs it)" >&2; exit 1; }
  echo "creating .venv with $PY"
  rm -rf .venv
  "$PY" -m venv .venv
  .venv/bin/python -m pip install -q --upgrade pip
fi

EXTRAS="${GOMU_EXTRAS:-test,ident,exchange,uq}"
STAMP=".venv/.gomu-installed"
WANT="$(cat pyproject.toml | sha1sum | cut -c1-16)-$EXTRAS"
if [ ! -f "$STAMP" ] || [ "$(cat "$STAMP")" != "$WANT" ]; then
  echo "installing gomu[$EXTRAS] into .venv"
  .venv/bin/python -m pip install -q -e ".[$EXTRAS]"
  echo "$WANT" > "$STAMP"
fi
export MPLBACKEND=Agg
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}" OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"
