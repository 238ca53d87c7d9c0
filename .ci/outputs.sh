#!/usr/bin/env bash
# The CI build's outputs and their sha256 (docs/reproducibility.md): every file under
# data/processed/ and figures/ but the measured times (*timing*) and progress logs.
#   bash .ci/outputs.sh check   compare them with .ci/outputs.sha256, naming each difference
#   bash .ci/outputs.sh write   rewrite .ci/outputs.sha256 from them (a change meant to change results)
set -euo pipefail
cd "$(dirname "$0")/.."
manifest=.ci/outputs.sha256

outputs() {
  find data/processed figures -type f ! -name '*timing*' ! -name '*progress*' ! -name '.gitkeep' | LC_ALL=C sort
}

case "${1:-}" in
  write)
    outputs | xargs -d '\n' sha256sum > "$manifest.tmp"
    mv "$manifest.tmp" "$manifest"
    echo "outputs: $(wc -l < "$manifest") files written to $manifest"
    ;;
  check)
    status=0
    # Files the build wrote that the manifest lacks, and the other way round.
    if ! diff <(cut -c67- "$manifest") <(outputs) > /tmp/outputs.$$.diff; then
      echo "outputs: the files differ from $manifest (< listed only, > written only):"
      grep '^[<>]' /tmp/outputs.$$.diff
      status=1
    fi
    rm -f /tmp/outputs.$$.diff
    # Bytes: sha256sum names each file that differs.
    sha256sum --quiet -c "$manifest" 2>/dev/null || status=1
    [ "$status" -eq 0 ] && echo "outputs: $(wc -l < "$manifest") files as in $manifest"
    exit "$status"
    ;;
  *)
    echo "usage: bash .ci/outputs.sh check|write" >&2
    exit 2
    ;;
esac
