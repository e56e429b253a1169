//! The readers' errors (issue 66): a file being read that cannot be read says
//! "cannot read", never "cannot write", missing or not the table it should be,
//! for both readers.
#![cfg(feature = "read")]

#[test]
fn a_file_that_cannot_be_read_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("none.mcap");
    let text = dir.path().join("trace.arrow");
    std::fs::write(&text, "t,theta1\n0,1\n").unwrap();
    let errors = [
        tables::mcap::read_mcap(&missing).unwrap_err(),
        tables::mcap::read_mcap(&text).unwrap_err(),
        tables::arrow::read_arrow(&missing).unwrap_err(),
        tables::arrow::read_arrow(&text).unwrap_err(),
        tables::arrow::read_arrow_batch(&text).unwrap_err(),
    ];
    for e in errors {
        let message = e.to_string();
        assert!(message.starts_with("cannot read ") && !message.contains("cannot write"), "{message}");
        assert!(message.contains("none.mcap") || message.contains("trace.arrow"), "names the file: {message}");
    }
}
