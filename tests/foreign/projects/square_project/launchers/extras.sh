#!/bin/bash
source /environment.sh
dt-launchfile-init
dt-exec roslaunch motion_control extras.launch veh:=$VEHICLE_NAME
dt-launchfile-join
