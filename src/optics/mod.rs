//! Optics: the display, the eye and the paraxial ray transfer between them (paper Sec. 2.3).
