# Two commands do all set-up: `make demo` and `make test` (both create .venv/ when missing).
PYTHON ?= python3
VENV := .venv
VPY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: venv demo test readme bench reproduce faces faces-groups pan-tilt rooms walks people-walks figures models soak clean

venv: $(STAMP)

$(STAMP): setup.py
	test -x $(VPY) || $(PYTHON) -m venv $(VENV)
	$(VPY) -m pip install --quiet --upgrade pip
	$(VPY) -m pip install --quiet -e ".[ros,test,cluster]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/ipomdp-gaze demo

# Every extra is installed here, so every test must run: IPOMDP_GAZE_REQUIRE_ROS turns a skip for a
# missing ROS (or cluster) package into a failure, and fails the run unless every collected ROS
# test ran and at least this many did (test/conftest.py counts them). The layer contract first
# (.importlinter, docs/design.md section 8), then the suite on one pytest-xdist worker more than
# the cores: the ROS tests spend much of their time waiting for DDS discovery and node start-up,
# which the extra worker fills (2 cores: 8 min 24 s with 2 workers, 6 min 56 s with 3; CPU 156%
# -> 182%); TEST_WORKERS=0 runs it in one process. A test file per worker at a time, so that a
# module's ROS nodes are shared by its tests; each worker reserves a ROS domain of its own. The package is
# compiled first: where PYTHONDONTWRITEBYTECODE is set (CI) an editable install is never compiled,
# and each of the suite's hundreds of node and CLI processes would compile it again (~0.2 s each).
REQUIRED_ROS_TESTS := 200
TEST_WORKERS ?= $(shell $(PYTHON) -c 'import os; print(len(os.sched_getaffinity(0)) + 1)')

test: $(STAMP)
	$(VENV)/bin/lint-imports
	$(VPY) -m compileall -q ipomdp_gaze
	IPOMDP_GAZE_REQUIRE_ROS=$(REQUIRED_ROS_TESTS) $(VPY) -m pytest -q \
		-n $(TEST_WORKERS) --dist loadfile test

# README.md's walkthrough: every shell command of its fenced blocks, in order, in one scratch
# folder; each transcript's shown lines compared with what its command prints (times and other
# values that vary masked); commands that cannot run here listed as skipped with the reason
# (bench/readme_walkthrough.py; README_MAX_SECONDS stops a command that runs longer).
README_MAX_SECONDS ?= 600

readme: $(STAMP)
	$(VPY) bench/readme_walkthrough.py --max-seconds $(README_MAX_SECONDS)

# The long robustness runs (minutes): 100,000 fuzzed frames, 10,080 hostile messages to the
# detector per mode, a minute of load at 1 kHz (11x11) and 60 Hz (256x256), 50 start/SIGTERM
# cycles, 1,000 examples per property test and fuzzed observation file, and the three-node face
# loop streaming at 30 Hz for 10 minutes (its section of docs/benchmarks.md).
soak: $(STAMP)
	$(VPY) -m pytest -q -s -m soak test
	PROPERTY_EXAMPLES=1000 $(VPY) -m pytest -q test/test_properties.py \
		test/test_robust_observation_files.py
	$(VPY) bench/ros/shutdown_cycles.py --cycles 50
	$(VPY) bench/ros/soak_face_loop.py --minutes 10

bench: $(STAMP)
	$(VPY) bench/run.py

reproduce: $(STAMP)
	$(VENV)/bin/ipomdp-gaze reproduce

# Face search, Haar and YuNet, on 300 held-out scenes per task, the pan/tilt search and the
# real-photo set: writes docs/faces.md and docs/data/faces.json (about 20 minutes), then the
# find --all group tables (faces-groups).
faces: $(STAMP)
	$(VPY) bench/faces/faces.py
	$(MAKE) faces-groups

# find --all on composed group pictures against the detector alone at 1, 1/2, 1/3, 1/4, training
# (photo and lfw faces; YuNet, then Haar) then test groups, each table in one run; then a small
# group of 15-40 px faces in a 4000x3000 face-free canvas (training, then test; find --all as
# shipped, --max-side 2048, and with --max-side 0 --min-face 15; about 1.7 GB resident for the
# full-resolution calls on 12 MP); then crowds: the split's photo faces 29 (25) times anywhere in
# 3000x2171 and 2048x1536 pictures at 50-100 px (25-50 px), find --all against the same without
# its crowd step (crowd ratio 0); then hard crowds (the faces grey, flat and blurred, 3000x2171
# and 2048x1536):
# docs/faces.md's section "find --all on groups: scale as an action" (about 11 minutes).
GROUP_BENCH := $(VPY) bench/faces/many_faces.py --scenes 8 --sizes 640x480,1280x886 --write docs/faces.md
CANVAS_BENCH := $(VPY) bench/faces/many_faces.py --canvas 15-40 --sizes 4000x3000 --scenes 4 \
	--min-face 15 --write docs/faces.md
CROWD_BENCH := $(VPY) bench/faces/many_faces.py --sizes 3000x2171,2048x1536 --scenes 4 \
	--crowd-ratios 0 --write docs/faces.md
# hard crowds: the faces grey, at 0.6 of their contrast, blurred (1 or 3 px of a 75 px face)
HARD_CROWD_BENCH := $(VPY) bench/faces/many_faces.py --sizes 3000x2171,2048x1536 --scenes 4 \
	--crowd 50-100 --write docs/faces.md
# a few people in a large photo: the split's photo faces 2-3 times at 100-200 px anywhere
SPARSE_BENCH := $(VPY) bench/faces/many_faces.py --sizes 4000x3000,3000x2171 --scenes 8 \
	--crowd 100-200 --write docs/faces.md
# ... smaller (60-120 px), and grey, faint and blurred (1 px of a 75 px face)
SPARSE_SMALL_BENCH := $(VPY) bench/faces/many_faces.py --sizes 4000x3000,3000x2171 --scenes 8 \
	--crowd 60-120 --write docs/faces.md
SPARSE_HARD_BENCH := $(VPY) bench/faces/many_faces.py --sizes 4000x3000 --scenes 8 \
	--crowd 100-200 --degrade 1 --write docs/faces.md
# a few small faces (25-50 px, 1/30 to 1/60 of the shorter side) anywhere in a photo of at most
# 2048 px, and a dozen of 30-60 px, grey, faint and blurred (1 px of a 75 px face)
FEW_SMALL_BENCH := $(VPY) bench/faces/many_faces.py --sizes 2048x1536,1600x1200 --scenes 8 \
	--crowd 25-50 --write docs/faces.md
FEW_HARD_BENCH := $(VPY) bench/faces/many_faces.py --sizes 1600x1200 --scenes 8 \
	--crowd 30-60 --degrade 1 --write docs/faces.md

faces-groups: $(STAMP)
	$(GROUP_BENCH) --split train --section groups-train-photos
	$(GROUP_BENCH) --split train --faces lfw --section groups-train-lfw
	$(GROUP_BENCH) --split train --detector haar --section groups-train-photos-haar
	$(GROUP_BENCH) --split train --faces lfw --detector haar --section groups-train-lfw-haar
	$(CANVAS_BENCH) --split train --section canvas-train
	$(GROUP_BENCH) --split test --section groups-test-photos
	$(GROUP_BENCH) --split test --detector haar --section groups-test-photos-haar
	$(CANVAS_BENCH) --split test --section canvas-test
	$(CROWD_BENCH) --split train --crowd 50-100 --copies 29 --section crowd-train
	$(CROWD_BENCH) --split train --crowd 25-50 --copies 25 --section crowd-train-small
	$(CROWD_BENCH) --split test --crowd 50-100 --copies 15 --section crowd-test
	$(CROWD_BENCH) --split test --crowd 25-50 --copies 13 --section crowd-test-small
	$(HARD_CROWD_BENCH) --split train --degrade 1 --copies 29 --section crowd-train-hard1
	$(HARD_CROWD_BENCH) --split train --degrade 3 --copies 29 --section crowd-train-hard3
	$(HARD_CROWD_BENCH) --split test --degrade 1 --copies 15 --section crowd-test-hard1
	$(HARD_CROWD_BENCH) --split test --degrade 3 --copies 15 --section crowd-test-hard3
	$(SPARSE_BENCH) --split train --copies 3 --section sparse-train
	$(SPARSE_BENCH) --split test --copies 2 --section sparse-test
	$(SPARSE_SMALL_BENCH) --split train --copies 3 --section sparse-small-train
	$(SPARSE_HARD_BENCH) --split train --copies 3 --section sparse-hard1-train
	$(SPARSE_SMALL_BENCH) --split test --copies 2 --section sparse-small-test
	$(SPARSE_HARD_BENCH) --split test --copies 2 --section sparse-hard1-test
	$(FEW_SMALL_BENCH) --split train --copies 5 --section few-small-train
	$(FEW_HARD_BENCH) --split train --copies 12 --section few-hard1-train
	$(FEW_SMALL_BENCH) --split test --copies 3 --section few-small-test
	$(FEW_HARD_BENCH) --split test --copies 6 --section few-hard1-test

# The pan/tilt face search against a blind sweep on 400 + 200 held-out scenes and a second camera:
# writes docs/pan_tilt.md and docs/data/pan_tilt.json.gz (10-30 minutes, and 15 for the ROS demo).
pan-tilt: $(STAMP)
	$(VPY) bench/pan_tilt/pan_tilt.py --ros-seeds 50

# Rooms of 0-4 faces (issue 37), both lenses: the many-target searches against one pass of the
# grouped sweep, with the every-view bounds on the first 100 rooms; writes docs/rooms.md
# (bench/pan_tilt/rooms.py; about 45 minutes on two idle cores).
rooms: $(STAMP)
	$(VPY) bench/pan_tilt/rooms.py --scenes 300 --bound 100

# People who move (issue 38): the tracker against track-last-detection on held-out walks at 5 and
# 15 deg/s; writes docs/walks.md (bench/pan_tilt/walks.py; about 40 minutes on two idle cores).
walks: $(STAMP)
	$(VPY) bench/pan_tilt/walks.py --scenes 50 --speeds 5,15

# Several people who move (issue 38): the many-target tracker against the one-target tracker and
# track-last-detection on held-out walks of two people at 5 and 15 deg/s; writes
# docs/people_walks.md (bench/pan_tilt/people_walks.py; about 15 minutes on two idle cores).
people-walks: $(STAMP)
	$(VPY) bench/pan_tilt/people_walks.py --scenes 30 --speeds 5,15

# Recalibrate every shipped Haar model and retrain faces-420-infomax from their recipes on training
# scenes, print what moved and install the new files (bench/faces/models.py; about 70 minutes).
# The figures README.md shows, each by the command its caption names (test/test_readme_figures.py
# checks that every caption's command still draws its figure).
figures: $(STAMP)
	$(VENV)/bin/ipomdp-gaze search --grid 11x11 --policy elm --seed 9 --plot docs/figures/search_example.png
	$(VENV)/bin/ipomdp-gaze demo --scene faces --seed 0 --plot docs/figures/annotated_camera.png
	$(VENV)/bin/ipomdp-gaze demo --scene faces --fovea --seed 0 --plot docs/figures/annotated_fovea.png

models: $(STAMP)
	$(VPY) bench/faces/models.py --install

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache
