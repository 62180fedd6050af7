//! The impulse-based multibody solver — being written (issue 4).
