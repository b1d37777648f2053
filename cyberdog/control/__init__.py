"""The controller layer: the diagonal trot (gait scheduler + foot trajectory + IK + PID + feedforward) that
turns time and the measured robot state into joint torques. Pure numpy, no simulator."""
