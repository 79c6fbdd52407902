#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# CTest cli.completion: the bash completion (app/completion.bash) against the built command.
#   bash test_completion.sh COMPLETION_SCRIPT UKDYN_DIR
set -euo pipefail
shopt -s extglob
PATH="$2:$PATH"
source "$1"
complete_words() {
  COMP_WORDS=("$@")
  COMP_CWORD=$((${#COMP_WORDS[@]} - 1))
  _ukdyn
  echo "${COMPREPLY[*]}"
}
expect() {
  local want=$1
  shift
  local got
  got=$(complete_words "$@")
  if [[ $got != "$want" ]]; then
    echo "completing '$*': got '$got', expected '$want'" >&2
    exit 1
  fi
}
expect "run" ukdyn ru
expect "--t-end" ukdyn run --t-e
expect "--plot-format" ukdyn sweep --plot-f
expect "pendulum pendulum_loop pendulum_on_rough_block" ukdyn run --example pendul
expect "double_four_bar double_four_bar_bodies double_four_bar_bodies_redundant double_four_bar_redundant" \
  ukdyn examples double_f
expect "svg" ukdyn sweep --plot-format s
expect "paper" ukdyn run --plot-style p
echo "completion ok"
