# eulertop in a container: for instructors on macOS or Windows (bubblewrap is Linux-only), or
# anyone who wants the grader kept apart from their own machine. README: "Grading on macOS,
# Windows or in a container".
#
#   docker build -t eulertop .
#   docker run --rm -v "$PWD":/work eulertop grade HW submissions
#
# Inside Docker's default seccomp profile no user namespace can be made, so bubblewrap cannot
# start: eulertop grades in its container mode (as root in the container, each student's kernel
# runs as a uid of its own never used before, with resource limits and the seccomp filter, the
# assignment, submissions and output folders private to root during the run). `eulertop doctor`
# inside the container says which tier it found.
FROM python:3.11-slim

# bubblewrap: used where the container is allowed namespaces (`--security-opt seccomp=unconfined`)
RUN apt-get update \
    && apt-get install -y --no-install-recommends bubblewrap \
    && rm -rf /var/lib/apt/lists/*

WORKDIR /opt/eulertop
COPY pyproject.toml README.md ./
COPY solver ./solver
COPY problems ./problems
COPY grader ./grader
COPY eulertop ./eulertop
COPY eulertop_base ./eulertop_base
RUN pip install --no-cache-dir . && rm -rf /opt/eulertop/build

# the instructor's folder is mounted here; every path on the command line is relative to it
WORKDIR /work
ENTRYPOINT ["eulertop"]
CMD ["--help"]
