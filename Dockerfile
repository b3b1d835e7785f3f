# fenics-garment on Debian's FEniCSx packages (the "Debian route"; the PyPI route is `make demo`).
#
# Base image: Debian unstable (sid) is the only Debian suite with DOLFINx 0.11
# (python3-dolfinx-real 0.11.0.post0, PETSc 3.25, Python 3.14, Open MPI); trixie has DOLFINx 0.9.
# The tag pins the base by the date it was bootstrapped, because sid moves every day.
# `.ci/docker-check` (`make docker-check`) creates it locally when it is missing, with
#     debootstrap --variant=minbase sid DIR http://deb.debian.org/debian
#     tar -C DIR -c . | docker import - debian:sid-20261123
# (no image registry is needed). To move to a newer sid, bootstrap a new date tag and change
# this line and BASE_IMAGE in .ci/docker-check together.
#
# Build and run (see docs/guide/install.md, "Docker image"):
#     docker build -t fenics-garment:0.1.0 .
#     docker run --rm -v "$PWD/out:/home/garment/output" fenics-garment:0.1.0
FROM debian:sid-20261123

ARG DEBIAN_FRONTEND=noninteractive

# One apt layer with the whole numerical stack, so that changing the package's sources never
# re-downloads it. gcc + libc6-dev + python3-dev are for the FFCx JIT (it compiles every form
# through cffi); openmpi-bin gives `mpirun`; python3-setuptools builds the package offline
# (`--no-build-isolation` below): only the libigl step below reaches PyPI.
# The sid index here can be older than its Valid-Until date, hence Check-Valid-Until=false.
RUN apt-get -o Acquire::Check-Valid-Until=false update \
 && apt-get install -y --no-install-recommends \
        python3-dolfinx-real \
        python3-gmsh \
        python3-meshio \
        python3-trimesh \
        python3-ezdxf \
        python3-h5py \
        python3-scipy \
        python3-matplotlib \
        python3-pytest \
        python3-pip \
        python3-setuptools \
        python3-dev \
        gcc \
        libc6-dev \
        openmpi-bin \
        ca-certificates \
 && apt-get clean \
 && rm -rf /var/lib/apt/lists/*

# Open MPI refuses to start as root without these (containers run as root by default).
# HOME and XDG_CACHE_HOME give the FFCx JIT a writable cache (~/.cache/fenics) also when the
# container runs as another user (`docker run --user "$(id -u):$(id -g)" ...`): both folders are
# world-writable with the sticky bit, like /tmp.
ENV OMPI_ALLOW_RUN_AS_ROOT=1 \
    OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
    HOME=/home/garment \
    XDG_CACHE_HOME=/home/garment/.cache \
    MPLBACKEND=Agg \
    PYTHONUNBUFFERED=1

# What pyproject needs and Debian does not package, from PyPI, without dependencies (they come
# from apt above): libigl (the body-surface distance search, an abi3 wheel). This is the only
# step that reaches PyPI (https). Behind a TLS-intercepting proxy pass its CA certificates as
# PEM text: `--build-arg EXTRA_CA_CERTS="$(cat /usr/local/share/ca-certificates/*.crt)"`
# (.ci/docker-check does). They are used for this pip call only and not kept in the image (the
# build argument does show in `docker history`; CA certificates are public).
ARG EXTRA_CA_CERTS=""
RUN set -e; \
    if [ -n "$EXTRA_CA_CERTS" ]; then \
        printf '%s\n' "$EXTRA_CA_CERTS" | cat /etc/ssl/certs/ca-certificates.crt - > /tmp/ca-bundle.pem; \
        export PIP_CERT=/tmp/ca-bundle.pem; \
    fi; \
    python3 -m pip install --no-deps --no-cache-dir --break-system-packages \
        --root-user-action=ignore "libigl==2.6.3"; \
    rm -f /tmp/ca-bundle.pem; \
    python3 -c "import igl; igl.AABB()"

# The package itself, without dependencies: DOLFINx, PETSc, MPI, gmsh, meshio, numpy and scipy
# come from apt above, and pyproject's `dolfinx-solver-real` (the PyPI wheel of the same stack)
# must not be pulled in next to them. fenics_garment/_stack.py detects which stack it runs on.
# Debian's Python is "externally managed" (PEP 668), hence --break-system-packages; it installs
# into /usr/local, apart from the apt-managed /usr. The sources stay in /opt/fenics-garment
# (tests, demos, meshes) for `docker run ... python3 -m pytest /opt/fenics-garment/tests`.
COPY . /opt/fenics-garment
RUN python3 -m pip install --no-deps --no-build-isolation --no-cache-dir \
        --break-system-packages --root-user-action=ignore /opt/fenics-garment \
 && rm -rf /opt/fenics-garment/build /opt/fenics-garment/*.egg-info \
 && mkdir -p /home/garment/output /home/garment/.cache \
 && chmod 1777 /home/garment /home/garment/output /home/garment/.cache \
 && fenics-garment --version

WORKDIR /home/garment

# The main demo on two ranks; it writes to output/ = /home/garment/output (mount a host folder
# there to keep the results).
CMD ["mpirun", "-n", "2", "python3", "-m", "fenics_garment.cli", "demo"]
