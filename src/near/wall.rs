//! A sphere above a no-slip plane wall.
