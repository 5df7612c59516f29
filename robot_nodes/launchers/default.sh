#!/bin/bash

source /environment.sh

# initialize launch file
dt-launchfile-init

# The course's task: wait, three sides of a square, back home, a clockwise circle.
# VEHICLE_NAME is the robot's name (set by Duckietown; the nodes run under /$VEHICLE_NAME/).
dt-exec roslaunch course_nodes course.launch veh:="$VEHICLE_NAME" mission:=square_then_circle

# wait for app to end
dt-launchfile-join
