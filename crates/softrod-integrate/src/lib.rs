//! softrod-integrate (in progress).
