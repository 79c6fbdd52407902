#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Builds the API reference, failing on any warning:
#   C++     Doxygen on the public headers include/ukdyn/** (docs/Doxyfile) -> OUT/cpp/html
#   Python  Sphinx autodoc on the built module (docs/api)                 -> OUT/python
# usage: scripts/build-docs.sh [BUILD_DIR [OUT]]   (BUILD_DIR default build, with the Python
# module built: cmake --build build --target ukdyn_python; OUT default BUILD_DIR/docs)
# Debian's doxygen and python3-sphinx (scripts/install-deps.sh). UKDYN_DOXYGEN_STRICT=1 (the
# test docs.api_reference) also fails on a public member without a doc comment of its own
# (docs/Doxyfile, EXTRACT_ALL).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(realpath -m "${1:-$root/build}")
out=$(realpath -m "${2:-$build/docs}")
version=$(sed -n 's/^project(ukdyn VERSION \([0-9.]*\).*/\1/p' "$root/CMakeLists.txt")

command -v doxygen >/dev/null || { echo "build-docs: doxygen not found (apt-get install doxygen)" >&2; exit 1; }
/usr/bin/python3 -c "import sphinx" 2>/dev/null ||
  { echo "build-docs: Sphinx not found (apt-get install python3-sphinx)" >&2; exit 1; }
[ -f "$build/python/ukdyn/__init__.py" ] ||
  { echo "build-docs: no Python module in $build/python (cmake --build $build --target ukdyn_python)" >&2; exit 1; }

rm -rf "$out/cpp" "$out/python" "$out/python-doctrees" "$out/doxygen-warnings.log"
mkdir -p "$out"
extract_all=YES
if [ "${UKDYN_DOXYGEN_STRICT:-0}" = 1 ]; then extract_all=NO; fi
echo "build-docs: C++ (doxygen $(doxygen --version)) -> $out/cpp/html"
(cd "$root" && UKDYN_DOCS_OUT="$out" UKDYN_VERSION="$version" UKDYN_DOXYGEN_EXTRACT_ALL=$extract_all \
  doxygen docs/Doxyfile)
if [ -s "$out/doxygen-warnings.log" ]; then
  cat "$out/doxygen-warnings.log" >&2
  echo "build-docs: doxygen warned (above)" >&2
  exit 1
fi
echo "build-docs: Python (sphinx $(/usr/bin/python3 -c 'import sphinx; print(sphinx.__version__)')) -> $out/python"
PYTHONPATH="$build/python" MPLBACKEND=Agg /usr/bin/python3 -m sphinx -W --keep-going -q -b html \
  -d "$out/python-doctrees" "$root/docs/api" "$out/python"
echo "build-docs: $out/cpp/html/index.html, $out/python/index.html"
