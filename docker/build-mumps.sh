#!/bin/sh
# Build Debian's MUMPS source (5.7.3) again with the METIS and SCOTCH orderings.
#
# Debian's libmumps-5.7 links neither, so MUMPS orders every factorisation with
# PORD.  On the No. 2 solid (404,844 DG unknowns) MUMPS's own choice, METIS, cuts
# the numeric factorisation by 25 % on one rank and 35 % on two (benchmarks/README.md,
# "MUMPS with METIS and SCOTCH").  The libraries keep Debian's sonames, so PETSc loads them
# in place of Debian's through LD_LIBRARY_PATH; nothing else changes.
#
#   sh docker/build-mumps.sh PREFIX     (as root, in the image's mumps stage)
set -eu
prefix=${1:?usage: build-mumps.sh PREFIX}
version=5.7.3
sha256=84a47f7c4231b9efdf4d4f631a2cae2bdd9adeaabc088261d15af040143ed112
url=http://deb.debian.org/debian/pool/main/m/mumps/mumps_${version}.orig.tar.gz

apt-get update
apt-get install -y --no-install-recommends ca-certificates curl gfortran libopenmpi-dev \
    libmetis-dev libscotch-dev libscalapack-openmpi-dev liblapack-dev libblas-dev make
work=$(mktemp -d)
cd "$work"
curl -fsSL --retry 3 -o mumps.tar.gz "$url"
echo "$sha256  mumps.tar.gz" | sha256sum -c -
tar xzf mumps.tar.gz
cd "MUMPS_$version"
# Debian's own settings file, position-independent, no OpenMP (one thread per rank)
sed -e 's/^OPTF .*/OPTF = -O2 -fPIC -fallow-argument-mismatch/' \
    -e 's/^OPTC .*/OPTC = -O2 -fPIC/' \
    -e 's/^OPTL .*/OPTL = -O2/' \
    -e 's|^LSCOTCHDIR.*|LSCOTCHDIR = /usr/lib/x86_64-linux-gnu|' \
    Make.inc/Makefile.debian.PAR > Makefile.inc
# the build's thousands of gfortran warnings (argument mismatches, harmless) go to a
# file, so the image build's log stays readable; its tail is shown if the build fails
if ! make -j"$(nproc)" d > build.log 2>&1; then
    tail -n 80 build.log
    echo "build-mumps.sh: MUMPS $version did not build; the last lines of its log are above" >&2
    exit 1
fi
echo "build-mumps.sh: MUMPS $version built with METIS and SCOTCH" \
    "($(grep -c -i 'warning' build.log || true) compiler warning lines, not shown)"
cd lib
mkdir -p "$prefix"
orderings="-lmetis -lesmumps -lscotch -lscotcherr"
mpif90 -shared -o "$prefix/libpord-5.7.so" -Wl,-soname,libpord-5.7.so \
    -Wl,--whole-archive libpord.a -Wl,--no-whole-archive
mpif90 -shared -o "$prefix/libmumps_common-5.7.so" -Wl,-soname,libmumps_common-5.7.so \
    -Wl,--whole-archive libmumps_common.a -Wl,--no-whole-archive \
    -L"$prefix" -lpord-5.7 $orderings -lpthread
mpif90 -shared -o "$prefix/libdmumps-5.7.so" -Wl,-soname,libdmumps-5.7.so \
    -Wl,--whole-archive libdmumps.a -Wl,--no-whole-archive \
    -L"$prefix" -lmumps_common-5.7 -lpord-5.7 -lscalapack-openmpi -llapack -lblas \
    $orderings -lpthread
rm -rf "$work"
