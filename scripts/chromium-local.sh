#!/usr/bin/env bash
# Headless Chromium for the report's browser test (tests/report_browser.rs): the test renders the
# report's pages, takes screenshots and reads the rendered DOM.
#
#   scripts/chromium-local.sh install   install Debian's chromium if no browser is found
#                                       (apt-get, as root; about a minute once, nothing after)
#   scripts/chromium-local.sh status    print the browser's path and version; exit 1 if none
#
# The browser is looked up as $WETGRAN_CHROMIUM, then chromium, chromium-browser,
# google-chrome on the PATH (the test looks it up the same way). Nothing is started here: the
# test starts each headless run itself, with a fresh profile folder.
#
# Exit status: 0 a browser is there; 1 none; 3 not root (and none installed); 4 the package
# cannot be installed.
set -euo pipefail

log() { echo "chromium-local: $*" >&2; }

find_browser() {
    if [[ -n "${WETGRAN_CHROMIUM:-}" && -x "${WETGRAN_CHROMIUM}" ]]; then
        echo "$WETGRAN_CHROMIUM"
        return 0
    fi
    local b
    for b in chromium chromium-browser google-chrome; do
        if command -v "$b" >/dev/null 2>&1; then
            command -v "$b"
            return 0
        fi
    done
    return 1
}

status() {
    local b
    if ! b=$(find_browser); then
        log "no chromium found"
        return 1
    fi
    echo "$b: $("$b" --version 2>/dev/null || echo 'version unknown')"
}

install() {
    if find_browser >/dev/null; then
        status
        return 0
    fi
    if [[ $(id -u) -ne 0 ]]; then
        log "no chromium found and not root: install it (apt-get install chromium) or set WETGRAN_CHROMIUM"
        return 3
    fi
    local log_file
    log_file=$(mktemp /tmp/chromium-local-apt.XXXXXX)
    export DEBIAN_FRONTEND=noninteractive
    log "installing chromium (apt-get, log in $log_file)"
    if ! apt-get install -y -qq --no-install-recommends chromium fonts-dejavu-core >"$log_file" 2>&1; then
        log "apt-get install failed; updating the package lists and trying again"
        if ! { apt-get update -qq && apt-get install -y -qq --no-install-recommends chromium fonts-dejavu-core; } \
            >>"$log_file" 2>&1; then
            tail -n 20 "$log_file" >&2
            return 4
        fi
    fi
    status
}

case "${1:-}" in
    install) install ;;
    status) status ;;
    *)
        echo "usage: $0 install|status" >&2
        exit 2
        ;;
esac
