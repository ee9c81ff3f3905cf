#!/usr/bin/env bash
# Build or reuse the hfcdem image and run commands in it with the checkout mounted.
#
#   docker/container.sh image            build (or reuse) the dependency image
#   docker/container.sh full-image       build the image with hfcdem installed
#   docker/container.sh run CMD...       run CMD inside, cwd mapped into the checkout
#   docker/container.sh shell            interactive shell inside
#   docker/container.sh engine           print the engine that would be used
#
# With a Docker engine: docker build / docker run.  Without one: podman build and
# buildah run (chroot isolation), creating debian:trixie-slim with debootstrap when
# no registry image can be pulled.  Environment:
#   HFCDEM_ENGINE=docker|podman   force an engine
#   HFCDEM_STORAGE=DIR            podman graph root (default /var/tmp/hfcdem-containers)
#   HFCDEM_MIN_FREE_GB=N          refuse to build with less free disk (default 10)
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
top=$(cd "$here/.." && pwd)
base_ref=docker.io/library/debian:trixie-slim
# The dependency image is named by the content of the Dockerfile's base stage (and
# the MUMPS build script it runs), so editing the dependency list builds a new image
# and an unchanged one is reused.
dockerfile_hash=$({ sed '/^FROM base AS hfcdem/q' "$here/Dockerfile"; cat "$here/build-mumps.sh"; } \
    | sha256sum | cut -c1-12)
image=localhost/hfcdem-base:$dockerfile_hash
full_image=localhost/hfcdem:latest

say() { printf '[hfcdem-image] %s\n' "$*" >&2; }
die() { printf '[hfcdem-image] error: %s\n' "$*" >&2; exit 1; }

have() { command -v "$1" >/dev/null 2>&1; }

engine=""
pick_engine() {
    if [ -n "${HFCDEM_ENGINE:-}" ]; then engine=$HFCDEM_ENGINE; return; fi
    if have docker && docker info >/dev/null 2>&1; then engine=docker; return; fi
    if ! { have podman && have buildah; }; then
        install_podman
    fi
    engine=podman
}

install_podman() {
    if [ "$(id -u)" != 0 ] || ! have apt-get; then
        die "no Docker engine, and podman/buildah are missing; install docker, or podman + buildah + debootstrap (needs root and apt-get)"
    fi
    say "no Docker engine: installing podman, buildah, debootstrap with apt-get"
    export DEBIAN_FRONTEND=noninteractive
    { apt-get update -qq && apt-get install -y -qq podman buildah debootstrap >/dev/null; } \
        || die "could not install podman/buildah/debootstrap with apt-get"
}

setup_podman_storage() {
    [ "$(id -u)" = 0 ] || return 0   # rootless podman keeps the user's own storage
    local root=${HFCDEM_STORAGE:-/var/tmp/hfcdem-containers}
    mkdir -p "$root"
    # overlay: a layer per change costs only the change (vfs copies ~4 GB per layer)
    cat >"$root/storage.conf" <<EOF
[storage]
driver = "overlay"
graphroot = "$root/graph"
runroot = "$root/run"
EOF
    export CONTAINERS_STORAGE_CONF=$root/storage.conf
    storage_dir=$root
}

storage_dir=/var/lib/docker
check_disk() {
    local need=${HFCDEM_MIN_FREE_GB:-10} dir=$storage_dir
    while [ ! -d "$dir" ]; do dir=$(dirname "$dir"); done
    local free_kb
    free_kb=$(df -Pk "$dir" | awk 'NR==2 {print $4}')
    if [ "$free_kb" -lt $((need * 1024 * 1024)) ]; then
        die "only $((free_kb / 1024 / 1024)) GB free under $dir; the image build needs ${need} GB (set HFCDEM_MIN_FREE_GB to override)"
    fi
}

image_exists() {
    if [ "$engine" = docker ]; then docker image inspect "$1" >/dev/null 2>&1
    else podman image exists "$1"; fi
}

ensure_base_podman() {
    image_exists "$base_ref" && return 0
    say "pulling $base_ref"
    if timeout 120 podman pull -q "$base_ref" >/dev/null 2>&1; then return 0; fi
    have debootstrap || die "cannot pull $base_ref and debootstrap is missing (apt-get install debootstrap)"
    [ "$(id -u)" = 0 ] || die "cannot pull $base_ref; creating it with debootstrap needs root"
    local rootfs
    rootfs=$(mktemp -d /var/tmp/hfcdem-rootfs.XXXXXX)
    say "no registry image: creating $base_ref with debootstrap (about 3 minutes)"
    if ! debootstrap --variant=minbase trixie "$rootfs" >"$rootfs.log" 2>&1; then
        tail -20 "$rootfs.log" >&2
        rm -rf "$rootfs"
        die "debootstrap of trixie failed (log above)"
    fi
    rm -rf "$rootfs"/var/lib/apt/lists/* "$rootfs"/var/cache/apt/archives/*.deb
    tar -C "$rootfs" -c . | podman import -q - "$base_ref" >/dev/null \
        || { rm -rf "$rootfs"; die "podman import of the debootstrap root failed"; }
    rm -rf "$rootfs" "$rootfs.log"
}

# build TARGET TAG: build into a temporary tag, check it, then give it the real
# name, so a failed or interrupted build never leaves an image that runs reuse.
build() {
    local target=$1 tag=$2 tmp="localhost/hfcdem-tmp:$$"
    check_disk
    say "building $tag (target $target) with $engine"
    local t0=$SECONDS
    if [ "$engine" = docker ]; then
        docker build --target "$target" -t "$tmp" -f "$here/Dockerfile" "$top" \
            || { docker rmi -f "$tmp" >/dev/null 2>&1 || true; die "image build failed (output above)"; }
        docker tag "$tmp" "$tag" && docker rmi "$tmp" >/dev/null
    else
        ensure_base_podman
        podman build --isolation chroot --network host --layers --target "$target" \
            -t "$tmp" -f "$here/Dockerfile" "$top" \
            || { podman rmi -f "$tmp" >/dev/null 2>&1 || true; die "image build failed (output above)"; }
        podman tag "$tmp" "$tag" && podman rmi "$tmp" >/dev/null
    fi
    say "built $tag in $((SECONDS - t0)) s"
}

ensure_image() {
    if image_exists "$image"; then return 0; fi
    build base "$image"
    # keep only the current dependency image (old ones are gigabytes each); an
    # image still used by a running container is left alone
    if [ "$engine" = podman ]; then
        podman images --format '{{.Repository}}:{{.Tag}}' | grep '^localhost/hfcdem-base:' \
            | grep -v ":$dockerfile_hash\$" | xargs -r podman rmi >/dev/null 2>&1 || true
    fi
}

# run_in IMAGE INTERACTIVE CMD: cwd maps to the same place relative to the checkout.
run_in() {
    local img=$1 interactive=$2; shift 2
    local rel=${PWD#"$top"}
    [ "$rel" = "$PWD" ] && rel=""
    local uid gid
    uid=$(stat -c %u "$top"); gid=$(stat -c %g "$top")
    local envs=(-e PYTHONPATH=/src -e XDG_CACHE_HOME=/src/.cache -e HOME=/tmp
                -e "CI=${CI:-}" -e "HFCDEM_RANKS=${HFCDEM_RANKS:-2}"
                -e "HFCDEM_PASS_LIMIT=${HFCDEM_PASS_LIMIT:-1800}")
    if [ "$engine" = docker ]; then
        local tty=()
        [ "$interactive" = 1 ] && tty=(-it)
        docker run --rm "${tty[@]}" --user "$uid:$gid" "${envs[@]}" \
            -v "$top:/src" -w "/src$rel" "$img" "$@"
    else
        local c rc=0 stamp
        stamp=$(mktemp)
        c=$(buildah from -q "$img")
        # shellcheck disable=SC2064
        trap "buildah rm $c >/dev/null 2>&1 || true; rm -f $stamp" EXIT
        local tty=()
        [ "$interactive" = 1 ] && tty=(-t)
        buildah run --isolation chroot --network host "${tty[@]}" "${envs[@]}" \
            -v "$top:/src" --workingdir "/src$rel" "$c" -- "$@" || rc=$?
        # chroot runs as root: hand files written into the checkout back to its owner
        if [ "$uid" != 0 ]; then
            find "$top" -newer "$stamp" -uid 0 -exec chown "$uid:$gid" {} + 2>/dev/null || true
        fi
        return $rc
    fi
}

cmd=${1:-}
[ -n "$cmd" ] && shift
case "$cmd" in
    engine) pick_engine; echo "$engine" ;;
    image)
        pick_engine; [ "$engine" = podman ] && setup_podman_storage
        ensure_image; echo "$image" ;;
    full-image)
        pick_engine; [ "$engine" = podman ] && setup_podman_storage
        build hfcdem "$full_image"; echo "$full_image" ;;
    run)
        [ $# -gt 0 ] || die "usage: container.sh run CMD..."
        pick_engine; [ "$engine" = podman ] && setup_podman_storage
        ensure_image
        run_in "$image" 0 "$@" ;;
    shell)
        pick_engine; [ "$engine" = podman ] && setup_podman_storage
        ensure_image
        run_in "$image" 1 bash ;;
    *) die "usage: container.sh image|full-image|run CMD...|shell|engine" ;;
esac
