#!/bin/bash

source /environment.sh

# initialize launch file
dt-launchfile-init

# launching app
dt-exec roslaunch motion_control square.launch veh:=$VEHICLE_NAME side:=0.6

# wait for app to end
dt-launchfile-join
