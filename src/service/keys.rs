//! API keys (docs/keys.md): `shapeflow keys create` makes a random key, shows it
//! once and stores only its SHA-256. Once a key exists (or `serve --token` is
//! given, an admin key that is not stored), every `/v1` route needs
//! `Authorization: Bearer KEY`; a job belongs to the key that created it and is
//! not found by other keys; an admin key sees and manages every job.

use super::store::{KeyRow, Store, StoreResult};
use sha2::{Digest, Sha256};
use std::collections::HashMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};
use subtle::ConstantTimeEq;

/// How long a key looked up (or found missing) is trusted before it is looked up
/// again: a revoked key stops working within this time on every node.
pub const KEY_CACHE: Duration = Duration::from_secs(1);

/// Keys remembered at most (a flood of wrong keys only clears the cache).
const CACHED_KEYS: usize = 10_000;

/// Who sends a request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Caller {
    /// No token and no key exist: the service is open to every client.
    Open,
    /// The `--token` of the service, or a key created with `--admin` (its name).
    Admin(Option<String>),
    /// A key: its name and its quotas (jobs accepted or running, bytes kept).
    Key { name: String, max_active: Option<i64>, max_storage: Option<i64> },
}

impl Caller {
    /// The owner of the jobs it creates.
    pub fn owner(&self) -> Option<&str> {
        match self {
            Caller::Open | Caller::Admin(None) => None,
            Caller::Admin(Some(name)) | Caller::Key { name, .. } => Some(name),
        }
    }

    /// Whether it sees and manages every job.
    pub fn sees_all(&self) -> bool {
        matches!(self, Caller::Open | Caller::Admin(_))
    }

    /// Whether it may see a job owned by `owner`.
    pub fn may_see(&self, owner: Option<&str>) -> bool {
        self.sees_all() || owner.is_some() && owner == self.owner()
    }

    pub fn max_active(&self) -> Option<i64> {
        match self {
            Caller::Key { max_active, .. } => *max_active,
            _ => None,
        }
    }

    pub fn max_storage(&self) -> Option<i64> {
        match self {
            Caller::Key { max_storage, .. } => *max_storage,
            _ => None,
        }
    }
}

/// Why a key cannot be created.
#[derive(Debug, thiserror::Error)]
pub enum KeyError {
    #[error("a key name is 1 to 64 letters, digits, `-`, `_` or `.`; got {0:?}")]
    BadName(String),
    #[error("a key named {0:?} exists already (revoked keys keep their names)")]
    Exists(String),
    #[error(transparent)]
    Store(#[from] super::store::StoreError),
}

/// What a new key may do: see everything, and its quotas.
#[derive(Debug, Clone, Copy, Default)]
pub struct Grant {
    pub admin: bool,
    pub max_active: Option<i64>,
    pub max_storage: Option<i64>,
}

/// Create the key `name` in `store`: the new key, to be shown once (only its hash
/// is stored).
pub async fn create(store: &Store, name: &str, grant: Grant) -> Result<String, KeyError> {
    let valid = |c: char| c.is_ascii_alphanumeric() || "-_.".contains(c);
    if name.is_empty() || name.len() > 64 || !name.chars().all(valid) {
        return Err(KeyError::BadName(name.into()));
    }
    let key = new_key();
    let row = KeyRow {
        name: name.into(),
        hash: key_hash(&key),
        admin: grant.admin,
        max_active: grant.max_active,
        max_storage: grant.max_storage,
        created_at: super::store::now(),
        revoked: false,
    };
    match store.insert_key(&row).await? {
        true => Ok(key),
        false => Err(KeyError::Exists(name.into())),
    }
}

/// A new key: `sf_` and 64 hex digits of 32 random bytes.
pub fn new_key() -> String {
    let mut bytes = [0u8; 32];
    getrandom::getrandom(&mut bytes).expect("the system's random source");
    format!("sf_{}", hex(&bytes))
}

/// The SHA-256 of a key, in hex: what is stored.
pub fn key_hash(key: &str) -> String {
    hex(&Sha256::digest(key.as_bytes()))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Looks up who a bearer key is, with what it found kept for [`KEY_CACHE`].
pub struct Keys {
    token: Option<String>,
    cached: Mutex<Cache>,
}

#[derive(Default)]
struct Cache {
    any: Option<(Instant, bool)>,
    by_hash: HashMap<String, (Instant, Option<KeyRow>)>,
}

impl Keys {
    /// With `token`: the service's admin token, compared in constant time.
    pub fn new(token: Option<String>) -> Keys {
        Keys { token, cached: Mutex::default() }
    }

    /// Whether requests need a key: a token is set, or a key exists.
    pub async fn required(&self, store: &Store) -> StoreResult<bool> {
        if self.token.is_some() {
            return Ok(true);
        }
        if let Some((at, any)) = self.cached.lock().unwrap().any {
            if at.elapsed() < KEY_CACHE {
                return Ok(any);
            }
        }
        let any = store.has_keys().await?;
        self.cached.lock().unwrap().any = Some((Instant::now(), any));
        Ok(any)
    }

    /// Who `bearer` is: `None` for no key of this service.
    pub async fn caller(&self, store: &Store, bearer: &str) -> StoreResult<Option<Caller>> {
        if let Some(token) = &self.token {
            if bool::from(bearer.as_bytes().ct_eq(token.as_bytes())) {
                return Ok(Some(Caller::Admin(None)));
            }
        }
        let hash = key_hash(bearer);
        let cached = self.cached.lock().unwrap().by_hash.get(&hash).filter(|(at, _)| at.elapsed() < KEY_CACHE).cloned();
        let key = match cached {
            Some((_, key)) => key,
            None => {
                let key = store.key_by_hash(&hash).await?;
                let mut cache = self.cached.lock().unwrap();
                if cache.by_hash.len() >= CACHED_KEYS {
                    cache.by_hash.clear();
                }
                cache.by_hash.insert(hash.clone(), (Instant::now(), key.clone()));
                key
            }
        };
        Ok(key.filter(|k| bool::from(k.hash.as_bytes().ct_eq(hash.as_bytes()))).map(|k| match k.admin {
            true => Caller::Admin(Some(k.name)),
            false => Caller::Key { name: k.name, max_active: k.max_active, max_storage: k.max_storage },
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_random_and_stored_as_their_hash() {
        let (a, b) = (new_key(), new_key());
        assert_ne!(a, b);
        assert_eq!(a.len(), 3 + 64);
        assert_eq!(key_hash(&a).len(), 64);
        assert_ne!(key_hash(&a), key_hash(&b));
        let key = Caller::Key { name: "ana".into(), max_active: None, max_storage: None };
        assert!(key.may_see(Some("ana")) && !key.may_see(Some("ben")) && !key.may_see(None));
        assert!(Caller::Admin(None).may_see(Some("ben")) && Caller::Open.may_see(None));
    }
}
