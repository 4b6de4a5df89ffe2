//! GIF animations.
