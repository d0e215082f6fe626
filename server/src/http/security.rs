//! Browser and network safety of every response (`docs/service.md`, security model):
//!
//! * a `Host` allow-list against DNS rebinding: loopback names, IP literals, the bound
//!   address, the machine's host name and `--allowed-host` names (a request without `Host`,
//!   which no browser sends, passes);
//! * state-changing methods (anything but GET, HEAD, OPTIONS) refused when the browser says
//!   the request is cross-site (`Sec-Fetch-Site: cross-site` or `same-site`) or its `Origin`
//!   is another origin or `null` — so no page on another origin can cancel or delete jobs
//!   with a body-less "simple" request; JSON bodies must also be `application/json`
//!   ([`crate::error::JsonBody`], 415), which no simple cross-site request can send;
//! * `X-Content-Type-Options: nosniff`, `X-Frame-Options: DENY`, `Referrer-Policy:
//!   no-referrer` and a `Content-Security-Policy` with `frame-ancestors 'none'` on every
//!   response (the dashboard's pages get the full [`DASHBOARD_CSP`]).

use axum::extract::{Request, State};
use axum::http::{HeaderMap, HeaderValue, Method, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use crate::config::Config;
use crate::error::ApiError;
use crate::server::AppState;

/// The policy of the dashboard's pages: its own scripts only (no inline script, no eval);
/// inline `style` attributes are allowed because the plots set colours and positions
/// through them; images from the API and `data:`/`blob:` URLs (downloads, SVG).
pub const DASHBOARD_CSP: &str = "default-src 'self'; script-src 'self'; style-src 'self' \
     'unsafe-inline'; img-src 'self' data: blob:; connect-src 'self'; object-src 'none'; \
     base-uri 'none'; form-action 'self'; frame-ancestors 'none'";

/// The policy of every other response.
pub const API_CSP: &str = "frame-ancestors 'none'";

/// The middleware: check the request, then add the headers to the response.
pub async fn guard(State(st): State<AppState>, req: Request, next: Next) -> Response {
    if let Err(e) = check_host(&st.cfg, req.headers()) {
        return with_headers(e.into_response());
    }
    if !is_safe(req.method())
        && let Err(e) = check_same_origin(req.headers())
    {
        return with_headers(e.into_response());
    }
    with_headers(next.run(req).await)
}

fn is_safe(m: &Method) -> bool {
    matches!(*m, Method::GET | Method::HEAD | Method::OPTIONS)
}

fn with_headers(mut resp: Response) -> Response {
    let h = resp.headers_mut();
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    if !h.contains_key(header::CONTENT_SECURITY_POLICY) {
        h.insert(
            header::CONTENT_SECURITY_POLICY,
            HeaderValue::from_static(API_CSP),
        );
    }
    resp
}

/// The host name of a `Host` value or URL authority, lower case, without the port
/// (`[::1]:8080` → `[::1]`, `Example.org:80` → `example.org`).
pub fn host_name(authority: &str) -> String {
    let a = authority.trim().to_ascii_lowercase();
    if a.starts_with('[') {
        match a.find(']') {
            Some(end) => a[..=end].to_string(),
            None => a,
        }
    } else {
        match a.rsplit_once(':') {
            Some((h, port)) if port.bytes().all(|b| b.is_ascii_digit()) => h.to_string(),
            _ => a,
        }
    }
}

/// Whether this server answers to `name` (a host name from [`host_name`]).
pub fn host_allowed(cfg: &Config, name: &str) -> bool {
    let bare = name.trim_start_matches('[').trim_end_matches(']');
    // An IP literal cannot be rebound: a page that reaches us by address is on our origin.
    if bare.parse::<std::net::IpAddr>().is_ok() {
        return true;
    }
    name == "localhost"
        || name.ends_with(".localhost")
        || cfg
            .allowed_hosts
            .iter()
            .any(|h| h == "*" || host_name(h) == name)
}

fn check_host(cfg: &Config, headers: &HeaderMap) -> Result<(), ApiError> {
    let Some(host) = headers.get(header::HOST) else {
        return Ok(());
    };
    let host = host
        .to_str()
        .map_err(|_| ApiError::Forbidden("the Host header is not text".into()))?;
    let name = host_name(host);
    if host_allowed(cfg, &name) {
        Ok(())
    } else {
        Err(ApiError::Forbidden(format!(
            "this server does not answer to the host `{name}` (a guard against DNS rebinding); \
             start it with `--allowed-host {name}` to reach it by that name"
        )))
    }
}

fn check_same_origin(headers: &HeaderMap) -> Result<(), ApiError> {
    let text = |n: header::HeaderName| headers.get(n).and_then(|v| v.to_str().ok());
    if let Some(site) = text(header::HeaderName::from_static("sec-fetch-site"))
        && matches!(site.trim(), "cross-site" | "same-site")
    {
        return Err(ApiError::Forbidden(format!(
            "cross-site requests may not change anything here (Sec-Fetch-Site: {site})"
        )));
    }
    if let Some(origin) = text(header::ORIGIN) {
        let origin = origin.trim();
        let authority = origin.split_once("://").map(|(_, a)| a);
        let same = match (authority, text(header::HOST)) {
            (Some(a), Some(host)) => a.eq_ignore_ascii_case(host.trim()),
            _ => false,
        };
        if !same {
            return Err(ApiError::Forbidden(format!(
                "requests from another origin may not change anything here (Origin: {origin})"
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn host_names_lose_their_port() {
        assert_eq!(host_name("127.0.0.1:8080"), "127.0.0.1");
        assert_eq!(host_name("[::1]:8080"), "[::1]");
        assert_eq!(host_name("Example.ORG"), "example.org");
        let cfg = Config::default();
        assert!(host_allowed(&cfg, "[::1]"));
        assert!(host_allowed(&cfg, "10.1.2.3"));
        assert!(host_allowed(&cfg, "localhost"));
        assert!(!host_allowed(&cfg, "evil.example"));
        let cfg = Config {
            allowed_hosts: vec!["lab.example:8080".into()],
            ..Config::default()
        };
        assert!(host_allowed(&cfg, "lab.example"));
    }
}
