//! Test hooks, not an API: pauses that tests ask for through an environment variable, so that a kill can land
//! inside a commit or a follower meets a slow disk. The one home of that mechanism (the store's writer and the
//! monitor's follower use it).

/// Sleeps for the number of milliseconds the environment variable `var` holds; unset, or not a number, means no
/// pause.
#[doc(hidden)]
pub fn pause_from_env(var: &str) {
    let ms = std::env::var(var).ok().and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
    if ms > 0 {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
}
