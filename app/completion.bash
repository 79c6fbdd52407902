# SPDX-License-Identifier: BSD-3-Clause
# bash completion for ukdyn, installed as /usr/share/bash-completion/completions/ukdyn.
# Subcommands, each subcommand's flags (read from `ukdyn SUB --help`, so they are always the
# command's own), example names (from `ukdyn examples`), the values of --format,
# --plot-format and --plot-style, directories after -o, and model files (*.yaml, *.yml, *.urdf) elsewhere.
_ukdyn() {
  local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD - 1]}
  local cmd=${COMP_WORDS[0]}
  if ((COMP_CWORD == 1)); then
    mapfile -t COMPREPLY < <(compgen -W "run sweep check linearize examples --help --version" -- "$cur")
    return
  fi
  local sub=${COMP_WORDS[1]}
  local examples
  case $prev in
    --example)
      examples=$("$cmd" examples 2>/dev/null | awk 'NF > 1 && $1 != "run" {print $1}')
      mapfile -t COMPREPLY < <(compgen -W "$examples" -- "$cur")
      return ;;
    -o | --output)
      mapfile -t COMPREPLY < <(compgen -d -- "$cur")
      return ;;
    --format)
      mapfile -t COMPREPLY < <(compgen -W "csv hdf5 csv,hdf5" -- "$cur")
      return ;;
    --plot-format)
      mapfile -t COMPREPLY < <(compgen -W "png pdf svg png,pdf png,svg" -- "$cur")
      return ;;
    --plot-style)
      mapfile -t COMPREPLY < <(compgen -W "screen paper" -- "$cur")
      return ;;
  esac
  if [[ $sub == examples ]]; then
    examples=$("$cmd" examples 2>/dev/null | awk 'NF > 1 && $1 != "run" {print $1}')
    mapfile -t COMPREPLY < <(compgen -W "$examples" -- "$cur")
    return
  fi
  if [[ $cur == -* ]]; then
    local flags
    flags=$("$cmd" "$sub" --help 2>/dev/null | grep -oE -- '--[a-z][a-z0-9-]*' | sort -u)
    mapfile -t COMPREPLY < <(compgen -W "$flags" -- "$cur")
    return
  fi
  mapfile -t COMPREPLY < <(compgen -d -- "$cur"; compgen -f -X '!*.@(yaml|yml|urdf)' -- "$cur")
}
complete -F _ukdyn ukdyn
