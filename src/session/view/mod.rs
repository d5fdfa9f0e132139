//! Episodes and benchmark results as pages in the browser (`coherent view`,
//! `coherent.view`): one self-contained HTML file per episode (two side by side, if
//! asked), an index of a results file with a page per episode, and a loopback server
//! that follows a results file as it grows.
//!
//! A front end asks with a [`ViewRequest`] (`request.rs`), the one way in: what to show
//! (files, an episode in memory, results lines), read within its limits, and whether it
//! wants the page, the files written or a server.
//!
//! - [`request`]: the request, and what comes back;
//! - [`read`]: what a file holds (a transcript or results), an episode read to show;
//! - [`pages`]: the pages, data in and HTML out, and how far a long one is;
//! - [`episode`]: what an episode's page shows, as data;
//! - [`events`]: the task's events where they happened, and the reference;
//! - [`scene`]: the scene at each step (pictures, positions, what robots hold);
//! - [`compare`]: two episodes together, and the first round they differ in;
//! - [`results`]: a results file's tables, figures and episodes;
//! - [`site`]: a results file's index and its episodes' pages, written to a folder;
//! - [`page`]: the HTML, its script and style (files in `assets/`, compiled in), the
//!   data embedded safely, the Content-Security-Policy;
//! - [`serve`]: the loopback server.

pub mod compare;
pub mod episode;
pub mod events;
pub mod page;
pub mod pages;
pub mod read;
pub mod request;
pub mod results;
pub mod scene;
pub mod serve;
pub mod site;

pub use self::episode::Given;
pub use self::pages::{Progress, Tell};
pub use self::request::{Source, ViewRequest, Written};
pub use self::site::Site;
