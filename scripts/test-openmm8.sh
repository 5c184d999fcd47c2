#!/usr/bin/env bash
# The whole suite against OpenMM 8: every C++ and Python test, the OpenCL ones through pocl,
# against Debian 13 (trixie)'s OpenMM 8.1.2, in a trixie root beside this system.
#  1. makes the root with 'debootstrap --variant=minbase trixie' from the Debian mirror this
#     system's apt uses (installing debootstrap first if needed), or reuses it: it lives in
#     $MRATTLE_TRIXIE_ROOT (default /var/cache/mrattle/trixie-root), outside the checkout;
#  2. copies a clean checkout of HEAD in (git archive: committed files only, no build folders),
#     and ../shared/deps beside it if there (openmmtools for the replica-exchange tests);
#  3. inside, runs scripts/install-deps.sh (the one list of packages; no apt once all is there)
#     and then the README's test command, scripts/test.sh (arguments go to its CTest).
# It mounts proc, sys and dev into the root and unmounts them on any exit. It needs root;
# when it cannot run (not root, no debootstrap, no reachable mirror) it says why and exits
# with 77. Set MRATTLE_DEBIAN_MIRROR to choose the mirror.
# Usage: scripts/test-openmm8.sh [CTest arguments, e.g. -R Python]
set -euo pipefail
{  # read whole before running: an edit to this file during a run does not change that run
repo="$(cd "$(dirname "$0")/.." && pwd)"
target="${MRATTLE_TRIXIE_ROOT:-/var/cache/mrattle/trixie-root}"
suite=trixie
marker="$target/.mrattle-bootstrap-complete"

skip() { echo "test-openmm8.sh: SKIPPED, the OpenMM 8 suite did not run: $*" >&2; exit 77; }
stamp() { date +%s; }
start=$(stamp)
phases=()
phase_done() { phases+=("$1: $(( $(stamp) - $2 )) s"); }

[ "$(id -u)" -eq 0 ] || skip "it needs root (debootstrap, mount, chroot); run it as root, e.g. with sudo"
for tool in chroot mount umount git tar flock; do
    command -v "$tool" >/dev/null 2>&1 || skip "'$tool' is not installed"
done
git -C "$repo" rev-parse --verify -q HEAD >/dev/null || skip "$repo is not a git checkout with a commit"

# The first Debian mirror apt uses for this system's own release (deb822 or one-line sources).
host_mirror() {
    local codename f deb822=() lines=()
    codename="$(. /etc/os-release && echo "${VERSION_CODENAME:-}")"
    for f in /etc/apt/sources.list.d/*.sources; do if [ -f "$f" ]; then deb822+=("$f"); fi; done
    for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do if [ -f "$f" ]; then lines+=("$f"); fi; done
    {
        awk -v c="$codename" '
            function emit() { if (uri != "" && (suites " ") ~ ("(^| )" c " ")) print uri; uri = ""; suites = "" }
            FNR == 1   { emit() }
            /^[ \t]*$/ { emit(); next }
            /^URIs:/   { uri = $2 }
            /^Suites:/ { suites = ""; for (i = 2; i <= NF; i++) suites = suites " " $i; suites = substr(suites, 2) }
            END        { emit() }' \
            "${deb822[@]}" /dev/null
        awk -v c="$codename" '$1 == "deb" { sub(/\[[^]]*\] */, ""); if ($3 == c) print $2 }' \
            "${lines[@]}" /dev/null
    } | head -n 1 || true
}

reachable() {  # url
    if command -v curl >/dev/null 2>&1; then curl -fsS --max-time 30 -o /dev/null "$1"
    elif command -v wget >/dev/null 2>&1; then wget -q -T 30 -O /dev/null "$1"
    else /usr/bin/python3 -c 'import sys, urllib.request; urllib.request.urlopen(sys.argv[1], timeout=30).read()' "$1"
    fi
}

mounted_under() { awk -v t="$1" '$2 == t || index($2, t "/") == 1 { found = 1 } END { exit !found }' /proc/mounts; }

unmount_all() {
    local m
    for m in dev sys proc; do
        if mounted_under "$target/$m"; then umount -R "$target/$m" 2>/dev/null || umount -R -l "$target/$m"; fi
    done
}

# One run at a time on a root.
mkdir -p "$(dirname "$target")"
exec 9>"$target.lock"
flock -n 9 || { echo "test-openmm8.sh: waiting for another run on $target"; flock 9; }
trap unmount_all EXIT
trap 'exit 130' INT TERM

t=$(stamp)
if [ -e "$marker" ]; then
    echo "=== Reusing the trixie root $target ($(cat "$target/etc/debian_version")) ==="
else
    mirror="${MRATTLE_DEBIAN_MIRROR:-$(host_mirror)}"
    [ -n "$mirror" ] || skip "no Debian mirror found in /etc/apt/sources.list or /etc/apt/sources.list.d/ (set MRATTLE_DEBIAN_MIRROR)"
    mirror="${mirror%/}"
    reachable "$mirror/dists/$suite/InRelease" || skip "the mirror $mirror is not reachable ($mirror/dists/$suite/InRelease)"
    if ! command -v debootstrap >/dev/null 2>&1; then
        echo "=== Installing debootstrap ==="
        { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap; } \
            || skip "debootstrap is not installed and apt could not install it"
    fi
    [ -e "/usr/share/debootstrap/scripts/$suite" ] || skip "this debootstrap does not know $suite (too old)"
    keyring=()
    [ -e /usr/share/keyrings/debian-archive-keyring.gpg ] && keyring=(--keyring=/usr/share/keyrings/debian-archive-keyring.gpg)
    unmount_all
    rm -rf --one-file-system "$target"
    echo "=== Making the $suite root $target from $mirror (debootstrap --variant=minbase) ==="
    debootstrap --variant=minbase "${keyring[@]}" "$suite" "$target" "$mirror" > "$target.debootstrap.log" 2>&1 || {
        tail -n 30 "$target.debootstrap.log"; echo "test-openmm8.sh: debootstrap failed (log: $target.debootstrap.log)" >&2; exit 1; }
    touch "$marker"
fi
phase_done bootstrap "$t"

unmount_all  # what a killed run left
mount -t proc proc "$target/proc"
mount --rbind /sys "$target/sys" && mount --make-rslave "$target/sys"
mount --rbind /dev "$target/dev" && mount --make-rslave "$target/dev"
cp -L /etc/resolv.conf "$target/etc/resolv.conf" 2>/dev/null || true

# A clean checkout of HEAD.
checkout=/opt/mrattle
rm -rf --one-file-system "$target$checkout"
mkdir -p "$target$checkout"
git -C "$repo" archive --format=tar HEAD | tar -x -C "$target$checkout"
if [ -n "$(git -C "$repo" status --porcelain --untracked-files=no)" ]; then
    echo "test-openmm8.sh: note: uncommitted changes in $repo are not tested (HEAD is)"
fi
# ../shared/deps beside the checkout (openmmtools and mpiplus, for the replica-exchange tests), as in CI.
shared="$target$(dirname "$checkout")/shared"
rm -rf --one-file-system "$shared"
if [ -d "$repo/../shared/deps" ]; then
    mkdir -p "$shared" && cp -a "$repo/../shared/deps" "$shared/deps"
fi
echo "=== Testing $(git -C "$repo" rev-parse --short HEAD) in $target$checkout ==="

in_root() {
    chroot "$target" /usr/bin/env -i HOME=/root LANG=C.UTF-8 TERM=dumb DEBIAN_FRONTEND=noninteractive \
        PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin /bin/bash -c "cd $checkout && $1" bash "${@:2}"
}

t=$(stamp)
echo "=== Dependencies (scripts/install-deps.sh in the root) ==="
# An install that a killed run left half done.
if [ -n "$(ls -A "$target/var/lib/dpkg/updates" 2>/dev/null)" ]; then in_root 'dpkg --configure -a'; fi
in_root ./scripts/install-deps.sh
phase_done dependencies "$t"
in_root 'echo "OpenMM $(/usr/bin/python3 -c "import openmm; print(openmm.version.short_version)"), $(/usr/bin/python3 --version), $(swig -version | grep -m1 Version)"'

t=$(stamp)
echo "=== Build (scripts/build.sh in the root) ==="
in_root ./scripts/build.sh
phase_done build "$t"

t=$(stamp)
echo "=== Tests (scripts/test.sh in the root) ==="
status=0
in_root './scripts/test.sh "$@"' "$@" || status=$?
phase_done tests "$t"
phases+=("total: $(( $(stamp) - start )) s")
echo "=== OpenMM 8 leg (trixie): $( [ $status -eq 0 ] && echo passed || echo FAILED ); ${phases[*]} ==="
exit $status
}
