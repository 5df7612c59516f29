#!/bin/bash

source /environment.sh

# initialize launch file
dt-launchfile-init

# The "D" variant of the course's task.
# VEHICLE_NAME is the robot's name (set by Duckietown; the nodes run under /$VEHICLE_NAME/).
dt-exec roslaunch course_nodes course.launch veh:="$VEHICLE_NAME" mission:=d_shape

# wait for app to end
dt-launchfile-join
