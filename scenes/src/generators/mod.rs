//! Procedural generators. (Being written.)
