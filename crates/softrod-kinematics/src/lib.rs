//! softrod-kinematics (in progress).
