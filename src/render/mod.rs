//! Rendering: display images (paper Sec. 3) and retinal images (paper Sec. 2.3, 4).
