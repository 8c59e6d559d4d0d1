//! Where the Green's-function cache lives when a command is given no directory: the environment, in order.

use std::ffi::OsString;
use std::path::PathBuf;

use metaplate_plate::default_cache_dir;

fn env(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<OsString> {
    let pairs: Vec<(String, OsString)> = pairs.iter().map(|(k, v)| ((*k).to_owned(), OsString::from(v))).collect();
    move |name| pairs.iter().find(|(k, _)| k == name).map(|(_, v)| v.clone())
}

#[test]
fn the_default_follows_the_environment_in_order() {
    let all = [("METAPLATE_CACHE_DIR", "/m"), ("XDG_CACHE_HOME", "/x"), ("HOME", "/h")];
    assert_eq!(default_cache_dir(env(&all)), Some(PathBuf::from("/m")));
    assert_eq!(default_cache_dir(env(&all[1..])), Some(PathBuf::from("/x/metaplate")));
    assert_eq!(default_cache_dir(env(&all[2..])), Some(PathBuf::from("/h/.cache/metaplate")));
    assert_eq!(default_cache_dir(env(&[])), None);
    // Empty is unset; a relative XDG_CACHE_HOME is ignored.
    let odd = [("METAPLATE_CACHE_DIR", ""), ("XDG_CACHE_HOME", "rel"), ("HOME", "/h")];
    assert_eq!(default_cache_dir(env(&odd)), Some(PathBuf::from("/h/.cache/metaplate")));
}
