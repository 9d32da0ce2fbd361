#!/usr/bin/env bash
# A cached Debian 13 (trixie) chroot with GIMP 3, for the ssn-shadow GIMP integration test.
#
# usage: gimp_chroot.sh build          create the chroot, or reuse a complete one (idempotent)
#        gimp_chroot.sh status         print "ready DIR" (exit 0) or "missing DIR" (exit 1)
#        gimp_chroot.sh path           print the chroot directory
#        gimp_chroot.sh run [VAR=VALUE ...] CMD [ARGS ...]
#                                      run CMD inside the chroot with a clean environment
#        gimp_chroot.sh gimp-eval CODE run CODE with gimp-console-3.0's python-fu-eval
#                                      (with SSN_GIMP_XVFB=1: under xvfb-run, so plug-in dialogs can open;
#                                      with SSN_GIMP_GUI=1: the full gimp-3.0 GUI under xvfb-run)
#                                      (GIMP3_DIRECTORY is taken from $SSN_GIMP3_DIRECTORY, a
#                                      path inside the chroot, when set; the plug-in's hooks
#                                      SSN_SHADOW_DIALOG_SELFTEST, SSN_SHADOW_DIALOG_SCREENSHOT and
#                                      SSN_SHADOW_SCREEN_SCREENSHOT are passed on when set)
#
# Environment: SSN_GIMP_CHROOT  the chroot (default /var/cache/ssn-shadow/gimp-trixie)
#              SSN_GIMP_MIRROR  the Debian mirror (default http://deb.debian.org/debian)
#              SSN_GIMP_SCREEN  the Xvfb screen, WIDTHxHEIGHTxDEPTH (default 1280x1024x24)
#
# Needs root (debootstrap, chroot, mount). The chroot is built in DIR.partial and renamed to
# DIR only after a stamp file is written, so an interrupted build is never mistaken for a
# complete one; the next build wipes DIR.partial (after checking nothing is mounted in it) and
# starts again. A lock file (DIR.lock) serialises concurrent builds. /proc and /dev are mounted
# into the chroot only inside a private mount namespace (unshare -m), so they disappear when
# the command ends, even if it is killed.
set -euo pipefail

DIR="${SSN_GIMP_CHROOT:-/var/cache/ssn-shadow/gimp-trixie}"
DIR="${DIR%/}"
MIRROR="${SSN_GIMP_MIRROR:-http://deb.debian.org/debian}"
PACKAGES=(gimp python3-gi gir1.2-gimp-3.0)
# xvfb + xauth: a virtual display for the dialog and undo tests (xvfb-run); xdotool presses Ctrl+Z.
EXTRA_PACKAGES=(xvfb xauth xdotool)
STAMP_NAME=".ssn-shadow-chroot"
STAMP_TEXT="ssn-shadow gimp chroot v3: debootstrap --variant=minbase trixie + ${PACKAGES[*]} ${EXTRA_PACKAGES[*]}"

die() { echo "gimp_chroot.sh: $*" >&2; exit 2; }

ready() {
    [ -f "$DIR/$STAMP_NAME" ] && [ "$(cat "$DIR/$STAMP_NAME")" = "$STAMP_TEXT" ] \
        && [ -x "$DIR/usr/bin/gimp-console-3.0" ]
}

need_root() {
    [ "$(id -u)" = 0 ] || die "needs root (debootstrap, chroot and mount)"
    for tool in unshare chroot mount findmnt flock; do
        command -v "$tool" >/dev/null || die "missing tool: $tool"
    done
}

mounted_under() {  # prints mount points at or below $1
    findmnt -rno TARGET | awk -v p="$1" '$0 == p || index($0, p "/") == 1'
}

safe_rm() {  # remove a directory tree, refusing if anything is mounted inside it
    local target="$1"
    [ -e "$target" ] || return 0
    if [ -n "$(mounted_under "$target")" ]; then
        die "refusing to delete $target: something is mounted inside it:
$(mounted_under "$target")"
    fi
    rm -rf --one-file-system "$target"
}

in_chroot() {  # in_chroot ROOT CMD...: run CMD in ROOT with /proc and /dev, private mounts
    local root="$1"; shift
    unshare --mount --propagation private /bin/sh -c '
        root="$1"; shift
        mount -t proc proc "$root/proc" || exit 3
        mount --rbind /dev "$root/dev" || exit 3
        exec chroot "$root" "$@"' sh "$root" "$@"
}

clean_env() {  # a minimal environment for commands inside the chroot
    echo /usr/bin/env -i PATH=/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin HOME=/root LANG=C.UTF-8
}

build() {
    need_root
    command -v debootstrap >/dev/null || die "missing tool: debootstrap (apt-get install debootstrap)"
    mkdir -p "$(dirname "$DIR")"
    exec 9>"$DIR.lock"
    flock 9
    if ready; then
        echo "$DIR"
        return 0
    fi
    local work="$DIR.partial" start=$SECONDS
    if [ -e "$work" ]; then
        echo "gimp_chroot.sh: removing the interrupted build $work" >&2
        safe_rm "$work"
    fi
    if [ -e "$DIR" ]; then
        echo "gimp_chroot.sh: $DIR is incomplete or from an older recipe; rebuilding" >&2
        safe_rm "$DIR"
    fi
    echo "gimp_chroot.sh: debootstrap trixie into $work" >&2
    # in a private mount namespace too: the /proc and /sys that debootstrap mounts in the target
    # vanish with it even if it is killed half-way
    unshare --mount --propagation private debootstrap --variant=minbase trixie "$work" "$MIRROR" >&2
    echo "gimp_chroot.sh: installing ${PACKAGES[*]} ${EXTRA_PACKAGES[*]}" >&2
    # shellcheck disable=SC2046
    in_chroot "$work" $(clean_env) DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -q --no-install-recommends "${PACKAGES[@]}" "${EXTRA_PACKAGES[@]}" >&2
    in_chroot "$work" $(clean_env) apt-get clean >&2
    [ -x "$work/usr/bin/gimp-console-3.0" ] || die "gimp-console-3.0 missing after install"
    echo "$STAMP_TEXT" > "$work/$STAMP_NAME"
    mv "$work" "$DIR"
    echo "gimp_chroot.sh: built $DIR in $((SECONDS - start)) s" >&2
    echo "$DIR"
}

cmd="${1:-}"
[ $# -gt 0 ] && shift
case "$cmd" in
    build) build ;;
    path) echo "$DIR" ;;
    status) if ready; then echo "ready $DIR"; else echo "missing $DIR"; exit 1; fi ;;
    run)
        need_root
        ready || die "no complete chroot at $DIR; run '$0 build' first"
        [ $# -gt 0 ] || die "run: no command given"
        # shellcheck disable=SC2046
        in_chroot "$DIR" $(clean_env) "$@"
        ;;
    gimp-eval)
        need_root
        ready || die "no complete chroot at $DIR; run '$0 build' first"
        [ $# -eq 1 ] || die "gimp-eval: give the Python code as one argument"
        extra=()
        [ -n "${SSN_GIMP3_DIRECTORY:-}" ] && extra+=("GIMP3_DIRECTORY=$SSN_GIMP3_DIRECTORY")
        # the plug-in's test hooks, its data folder, and the certificates a set-up inside needs to reach the index
        for name in SSN_SHADOW_DIALOG_SELFTEST SSN_SHADOW_DIALOG_SCREENSHOT SSN_SHADOW_SCREEN_SCREENSHOT \
            SSN_SHADOW_SETUP_TEST SSN_SHADOW_DATA SSL_CERT_FILE PIP_CERT; do
            [ -n "${!name:-}" ] && extra+=("$name=${!name}")
        done
        screen="${SSN_GIMP_SCREEN:-1280x1024x24}"
        [[ "$screen" =~ ^[0-9]+x[0-9]+x[0-9]+$ ]] || die "SSN_GIMP_SCREEN must read WIDTHxHEIGHTxDEPTH, not '$screen'"
        xvfb=()
        gimp=(gimp-console-3.0 -i)
        [ -n "${SSN_GIMP_XVFB:-}" ] && xvfb=(xvfb-run -a -n $((RANDOM % 700 + 200)) -s "-screen 0 $screen")
        if [ -n "${SSN_GIMP_GUI:-}" ]; then
            xvfb=(xvfb-run -a -n $((RANDOM % 700 + 200)) -s "-screen 0 $screen")
            gimp=(gimp-3.0 --no-splash)
        fi
        # shellcheck disable=SC2046
        in_chroot "$DIR" $(clean_env) "${extra[@]}" "${xvfb[@]}" \
            "${gimp[@]}" --batch-interpreter python-fu-eval -b "$1" --quit
        ;;
    *) sed -n '2,/^set -euo/p' "$0" | grep '^#' | sed 's/^# \{0,1\}//' >&2; exit 2 ;;
esac
