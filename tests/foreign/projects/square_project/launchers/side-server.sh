#!/bin/bash
source /environment.sh
dt-launchfile-init
dt-exec rosrun motion_msgs side_server.py
dt-launchfile-join
