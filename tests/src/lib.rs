//! Shared helpers of the validation suite; the cases live in `tests/*.rs`.
