//! Host side of the project (skeleton; see issue 5).
