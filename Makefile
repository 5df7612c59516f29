# The course's everyday commands. The first use of any target creates .venv and installs the
# project with the exact versions of constraints.txt; later uses reinstall only when
# pyproject.toml or constraints.txt change.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
# Jupyter refuses to run as root unless told; LAB_ARGS passes more options (--port=8890 ...).
LAB_ROOT := $(shell [ "$$(id -u)" = 0 ] && echo --allow-root)
LAB_ARGS ?=
# The folder JupyterLab shows: the repository (its course/ opens first).
LAB_DIR ?= $(CURDIR)

# Debian's ROS 1 (rospy, roscore, rosbag, genpy, the message packages whose md5 sums the tests
# compare with the course's), bubblewrap, the sandbox
# the autograder runs student code in, Chromium, the browser the JupyterLab tests drive, and
# ffmpeg, which writes animations as MP4.
ROS_PACKAGES := python3-rospy python3-rosbag python3-roslaunch ros-core python3-genpy \
	python3-genmsg python3-std-msgs python3-sensor-msgs python3-geometry-msgs python3-nav-msgs \
	python3-std-srvs python3-tf2-msgs python3-tf2-ros python3-tf bubblewrap python3-venv \
	chromium ffmpeg

.PHONY: help venv compiled run test test-fast lab hub robot ros lint format bench lock clean

help:
	@echo "make run     drive the square-then-circle task in the simulator (bag, plot, summary)"
	@echo "make test    run the whole test suite, on every core"
	@echo "make test-fast  the quick tests only: the library and the commands (under 2 minutes)"
	@echo "make lab     start JupyterLab on the course notebooks"
	@echo "make hub     run the class hub on this machine (as root; see the README)"
	@echo "make venv    create .venv with the project installed (every other target does it too)"
	@echo "make robot   ready robot_nodes/ for the robot (SOLUTION=course: with your notebooks)"
	@echo "make ros     install Debian's ROS 1, bubblewrap and Chromium (needs apt, root or sudo)"
	@echo "make lint    check and format the code with ruff"
	@echo "make bench   list the benchmarks (run one with: .venv/bin/duckie bench NAME)"
	@echo "make lock    refresh constraints.txt from the current environment"

$(STAMP): pyproject.toml constraints.txt
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' || \
		{ echo "The course needs Python 3.11 or newer; run with PYTHON=python3.11 (or newer)."; exit 1; }
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -c constraints.txt -e '.[dev]'
	@touch $(STAMP)

venv: $(STAMP)

run: $(STAMP)
	$(BIN)/duckie mission --out runs/latest

# Every core, and two workers more: while one waits (a browser, a ROS master, a time limit
# running out), the others keep the cores busy; more than that only share the same busy cores
# (make test's last line says how busy). pytest-xdist's workers take whole test modules
# (a module's shared setup is made once), the longest first (tests/conftest.py), so that they
# finish together.
WORKERS ?= $(shell echo $$(( $$(nproc) + 2 )))
PARALLEL ?= -n $(WORKERS) --dist loadscope --no-loadscope-reorder

# The project's modules compiled once, even where PYTHONDONTWRITEBYTECODE is set: the suite
# starts hundreds of Python processes (kernels, sandboxes, missions) that import them.
compiled: $(STAMP)
	@$(BIN)/python -m compileall -q duckielib autograder

test: compiled
	$(BIN)/python -m pytest $(PARALLEL)

# The quick loop while changing the library or the commands: everything but the slow tests
# (notebooks, grading, browsers, the real ROS master), in under two minutes.
test-fast: compiled
	$(BIN)/python -m pytest $(PARALLEL) -m "not slow and not notebook"

# JupyterLab as students use it: the repository's files (the README among them) with course/
# open, nbgrader's Validate checking every cell but not its instructor tools (duckielib/lab/),
# and the course's commands (duckie handin ...) in its terminals: each terminal runs your
# $SHELL with this PATH, .venv/bin first, even when no terminal started the server (JupyterLab
# would then open login shells, whose profile sets PATH anew; duckielib/lab/ tells it not to).
lab: $(STAMP)
	@test -d course || { echo "course/ has no released notebooks yet: see the README's status section."; exit 1; }
	PATH="$(CURDIR)/$(BIN):$$PATH" \
	JUPYTER_CONFIG_PATH="$(CURDIR)/duckielib/lab$${JUPYTER_CONFIG_PATH:+:$$JUPYTER_CONFIG_PATH}" \
		$(BIN)/jupyter lab --ServerApp.root_dir="$(LAB_DIR)" --LabApp.default_url=/lab/tree/course \
		$(LAB_ROOT) $(LAB_ARGS)

# The class hub: JupyterHub with nbgrader's exchange, on this machine (as root: JupyterHub
# starts each student's server as that student; Formgrader runs as the hub's own account).
# `duckie hub users ROSTER` first. It listens on 127.0.0.1:8000; HUB_ARGS passes more options
# (--ip 0.0.0.0 --port 8000 --hub /srv/duckiebot-hub); off this machine, serve it over HTTPS
# (see the README).
HUB_ARGS ?=
hub: $(STAMP)
	$(SUDO) $(BIN)/duckie hub start $(HUB_ARGS)

# The course library and a solution into robot_nodes/deploy/: the reference solution unless
# told (make robot SOLUTION=course).
robot: $(STAMP)
	$(BIN)/duckie robot prepare $(if $(SOLUTION),--solution $(SOLUTION))

ros:
	$(SUDO) apt-get update
	DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y --no-install-recommends $(ROS_PACKAGES)

lint: $(STAMP)
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

bench: $(STAMP)
	$(BIN)/duckie bench

lock: $(STAMP)
	$(BIN)/python -m pip freeze --exclude-editable > constraints.txt

clean:
	rm -rf $(VENV) runs .pytest_cache .ruff_cache .hypothesis
