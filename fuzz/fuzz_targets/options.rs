//! Any option name and text, as the command line and `snakegrid_options_set` receive them: an
//! error naming the parameter or a new valid value, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: (&str, &str)| {
    let (name, text) = input;
    let mut params = snakegrid::Params::default();
    let before = params.clone();
    match params.set(name, text) {
        Ok(()) => assert!(
            params.validate().is_ok(),
            "{name}={text:?} set an invalid value"
        ),
        Err(_) => assert_eq!(
            params, before,
            "a refused {name}={text:?} changed the parameters"
        ),
    }
});
