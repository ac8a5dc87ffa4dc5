//! softrod-dynamics (in progress).
