//! Doom 3 .af reader — being written (issue 2).
