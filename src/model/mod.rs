//! Assembly of a scene into the problems the series engine solves.
