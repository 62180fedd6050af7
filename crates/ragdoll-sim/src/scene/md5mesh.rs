//! md5mesh joints reader — being written (issue 2).
