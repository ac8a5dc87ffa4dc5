//! softrod-scene (in progress).
