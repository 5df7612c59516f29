#!/bin/bash

source /environment.sh

# initialize launch file
dt-launchfile-init

# The rotation task: a quarter turn clockwise, then back.
# VEHICLE_NAME is the robot's name (set by Duckietown; the nodes run under /$VEHICLE_NAME/).
# The run is recorded to /data/logs/ on the robot (copy it to the laptop for notebook 10).
BAG="/data/logs/course_$(date +%Y%m%d_%H%M%S).bag"
dt-exec roslaunch course_nodes course.launch veh:="$VEHICLE_NAME" bag:="$BAG" mission:=rotation

# wait for app to end
dt-launchfile-join
