//! A model server's base URL as the client uses it: the chat completions URL it posts to
//! (the path joined below the base's, the base's query kept: some gateways take their
//! key there), whether the URL carries a user and password (then sent as basic auth,
//! and no bearer key beside it), the secrets it holds, and the form in which it is shown
//! and stored: no user or password, and every query value redacted. Transcripts,
//! results lines, `--json` and messages only ever hold that form.

/// What a query value or a user's password is shown as.
const REDACTED: &str = "[redacted]";

/// The shortest query value that is also scrubbed from what the server says: a shorter
/// one (`?v=1`) is no secret, and replacing it everywhere would garble the text.
const SECRET_CHARS: usize = 8;

/// One base URL, parsed.
#[derive(Debug)]
pub(crate) struct Address {
    /// `<base path>/chat/completions`, with the base's query (and its user, which the
    /// HTTP client sends as basic auth).
    pub post: reqwest::Url,
    /// The base URL as shown and stored.
    pub shown: String,
    /// Whether the URL has a user or password.
    pub has_credentials: bool,
    /// Its password and its longer query values, to scrub from the server's words.
    pub secrets: Vec<String>,
}

impl Address {
    /// The base URL `base` (up to the version, e.g. `https://host/v1?key=...`).
    pub(crate) fn parse(base: &str) -> Result<Address, String> {
        let url = reqwest::Url::parse(base.trim())
            .ok()
            .filter(|u| matches!(u.scheme(), "http" | "https") && u.has_host())
            .ok_or_else(|| {
                format!(
                    "base URL {:?} is not a URL (http:// or https://, with a host)",
                    redacted(base)
                )
            })?;
        let mut post = url.clone();
        post.set_fragment(None);
        let path = url.path().trim_end_matches('/');
        post.set_path(&format!("{path}/chat/completions"));
        let mut secrets: Vec<String> = url.password().map(str::to_owned).into_iter().collect();
        secrets.extend(
            url.query_pairs()
                .map(|(_, v)| v.into_owned())
                .filter(|v| v.chars().count() >= SECRET_CHARS),
        );
        Ok(Address {
            post,
            shown: shown(&url),
            has_credentials: !url.username().is_empty() || url.password().is_some(),
            secrets,
        })
    }
}

/// `url` without user, password or fragment, each query value redacted.
fn shown(url: &reqwest::Url) -> String {
    let mut bare = url.clone();
    let _ = bare.set_username("");
    let _ = bare.set_password(None);
    bare.set_fragment(None);
    bare.set_query(None);
    let mut text = bare.as_str().to_owned();
    if let Some(query) = url.query() {
        let pairs: Vec<String> = query
            .split('&')
            .map(|pair| match pair.split_once('=') {
                Some((key, _)) => format!("{key}={REDACTED}"),
                None => pair.to_owned(),
            })
            .collect();
        text.push('?');
        text.push_str(&pairs.join("&"));
    }
    text
}

/// The base URL `base` as it may be shown: without user, password or fragment, every
/// query value redacted; text that is no URL is shown as it is, unless it holds a `?`
/// or an `@` (then it might hold a secret, and is not shown at all).
pub fn redacted(base: &str) -> String {
    match reqwest::Url::parse(base.trim()) {
        Ok(url) if url.has_host() => shown(&url),
        _ if base.contains(['?', '@']) => REDACTED.to_owned(),
        _ => base.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_path_is_joined_and_the_query_kept() {
        let a = Address::parse("http://h:8000/v1/?api-key=SECRET123&v=1").expect("a URL");
        assert_eq!(
            a.post.as_str(),
            "http://h:8000/v1/chat/completions?api-key=SECRET123&v=1"
        );
        assert_eq!(a.shown, "http://h:8000/v1/?api-key=[redacted]&v=[redacted]");
        assert_eq!(a.secrets, ["SECRET123"]);
        assert!(!a.has_credentials);
        let plain = Address::parse("https://api.openai.com/v1").expect("a URL");
        assert_eq!(
            plain.post.as_str(),
            "https://api.openai.com/v1/chat/completions"
        );
        assert_eq!(plain.shown, "https://api.openai.com/v1");
    }

    #[test]
    fn a_user_and_password_are_never_shown() {
        let a = Address::parse("http://me:pw-0123456789@10.0.0.2:8000/v1#x").expect("a URL");
        assert!(a.has_credentials);
        assert_eq!(a.shown, "http://10.0.0.2:8000/v1");
        assert_eq!(a.secrets, ["pw-0123456789"]);
        assert_eq!(
            redacted("http://me:pw@h/v1?k=abc"),
            "http://h/v1?k=[redacted]"
        );
        assert_eq!(redacted("not a url?key=x"), "[redacted]");
        assert_eq!(redacted("localhost:8000"), "localhost:8000");
        let e = Address::parse("ftp://me:pw@h/v1?k=s").expect_err("not http");
        assert!(!e.contains("pw") && !e.contains("k=s"), "{e}");
    }
}
