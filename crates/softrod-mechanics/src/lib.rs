//! softrod-mechanics (in progress).
