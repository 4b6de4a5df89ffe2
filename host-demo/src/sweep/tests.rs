//! Sweep files: expansion and errors.
