//! numpy arrays in and out, checked with messages that name the argument.
//!
//! Where values are copied:
//! * **Images out** (`render`, `approx`, `read_image`, the comparison's maps): never. The
//!   library's `Vec<[f32; 3]>` is reinterpreted as a `Vec<f32>` (bytemuck: same allocation) and
//!   handed to numpy, which keeps the Rust allocation alive as the array's buffer.
//! * **Images in** (`compare`, `write_image`, `RenderResult.write`): one copy, into the
//!   library's `RgbImage`, a `memcpy` for a C-contiguous float32 array; float64 (and strided)
//!   arrays are converted in the same single pass. The finiteness check reads numpy's buffer
//!   before the copy; float64 values are checked once more after rounding to float32, where a
//!   finite value beyond float32's range becomes infinite.
//! * **The FLIP map out** (`Comparison.flip_map`): one copy, since the comparison keeps its own
//!   for the gates and the report. The other maps are computed into new arrays on first use.
//! * **Particles in** (`Scene.from_arrays`): none for float32/float64 arrays in any layout; the
//!   values are read from numpy's buffer while the scene's particles are built (the scene
//!   itself is the library's own data). Lists and tuples become one float64 array first
//!   (`numpy.asarray`).
//! * **Particles out** (`Scene.particles`): the arrays are filled from the scene's particles
//!   once and handed to numpy without a further copy.

use crate::errors::input_error;
use numpy::ndarray::{Array, Array3, Dimension, NdIndex};
use numpy::{
    Element, PyArray, PyArrayDescrMethods, PyArrayMethods, PyReadonlyArray, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pgt::image_io::RgbImage;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// An image as a float32 array of shape (height, width, 3), without a copy.
pub fn image_to_array(py: Python<'_>, image: RgbImage) -> Bound<'_, PyArray<f32, numpy::Ix3>> {
    let (w, h) = (image.width as usize, image.height as usize);
    let values: Vec<f32> = bytemuck::allocation::cast_vec(image.pixels);
    let array =
        Array3::from_shape_vec((h, w, 3), values).expect("an RgbImage holds width × height pixels");
    PyArray::from_owned_array(py, array)
}

/// A vector of values as a numpy array of `shape` (its product must be the length), without a
/// copy.
pub fn vec_to_array<T: Element, D: Dimension>(
    py: Python<'_>,
    values: Vec<T>,
    shape: D,
) -> Bound<'_, PyArray<T, D>> {
    let array = Array::from_shape_vec(shape, values).expect("the shape fits the values");
    PyArray::from_owned_array(py, array)
}

/// One dimension an argument must have: any size (named in messages) or exactly this one.
#[derive(Debug, Clone, Copy)]
pub enum Size {
    Any(&'static str),
    Is(usize),
}

/// A shape for messages: "(n, 3)".
fn shape_text(parts: impl Iterator<Item = String>) -> String {
    let parts: Vec<String> = parts.collect();
    if parts.len() == 1 {
        format!("({},)", parts[0])
    } else {
        format!("({})", parts.join(", "))
    }
}

/// An argument as a numpy array: arrays as they are, anything else (lists, tuples, scalars)
/// through `numpy.asarray(x, dtype=float64)`.
fn as_numpy<'py>(name: &str, obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyUntypedArray>> {
    let py = obj.py();
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", "float64")?;
    let converted = py
        .import("numpy")?
        .getattr("asarray")?
        .call((obj,), Some(&kwargs))
        .map_err(|e| input_error(py, format!("{name}: expected an array of numbers ({e})")))?;
    Ok(converted.cast_into::<PyUntypedArray>()?)
}

/// A checked float array argument, float32 or float64 as the caller gave it, read in place.
pub enum Floats<'py, D: Dimension> {
    F32(PyReadonlyArray<'py, f32, D>),
    F64(PyReadonlyArray<'py, f64, D>),
}

impl<'py, D: Dimension> Floats<'py, D> {
    /// The value at `index`, as f64.
    #[inline]
    pub fn get<I: NdIndex<D> + Copy>(&self, index: I) -> f64 {
        match self {
            Floats::F32(a) => a.as_array()[index] as f64,
            Floats::F64(a) => a.as_array()[index],
        }
    }

    /// The array's shape.
    pub fn shape(&self) -> &[usize] {
        match self {
            Floats::F32(a) => a.shape(),
            Floats::F64(a) => a.shape(),
        }
    }

    /// The first non-finite value and its index (row-major), if any.
    fn first_non_finite(&self) -> Option<(usize, f64)> {
        match self {
            Floats::F32(a) => a
                .as_array()
                .iter()
                .enumerate()
                .find(|(_, v)| !v.is_finite())
                .map(|(i, v)| (i, *v as f64)),
            Floats::F64(a) => a
                .as_array()
                .iter()
                .enumerate()
                .find(|(_, v)| !v.is_finite())
                .map(|(i, v)| (i, *v)),
        }
    }
}

/// The argument `name` as a float32 or float64 array of `shape`, every value finite.
pub fn floats<'py, D: Dimension>(
    name: &str,
    obj: &Bound<'py, PyAny>,
    shape: &[Size],
) -> PyResult<Floats<'py, D>> {
    let py = obj.py();
    let array = as_numpy(name, obj)?;
    let got = array.shape().to_vec();
    let fits = got.len() == shape.len()
        && got.iter().zip(shape).all(|(g, w)| match w {
            Size::Any(_) => true,
            Size::Is(n) => g == n,
        });
    if !fits {
        let want = shape_text(shape.iter().map(|d| match d {
            Size::Any(free) => free.to_string(),
            Size::Is(n) => n.to_string(),
        }));
        let got_text = shape_text(got.iter().map(|n| n.to_string()));
        return Err(input_error(
            py,
            format!("{name}: expected an array of shape {want}, got shape {got_text}"),
        ));
    }
    let dtype = array.dtype();
    let values = if dtype.is_equiv_to(&numpy::dtype::<f64>(py)) {
        Floats::F64(readonly::<f64, D>(name, &array)?)
    } else if dtype.is_equiv_to(&numpy::dtype::<f32>(py)) {
        Floats::F32(readonly::<f32, D>(name, &array)?)
    } else {
        return Err(input_error(
            py,
            format!(
                "{name}: expected float32 or float64 values, got dtype {dtype} (convert with .astype(numpy.float64))"
            ),
        ));
    };
    if let Some((i, v)) = values.first_non_finite() {
        let width: usize = got.iter().skip(1).product::<usize>().max(1);
        let place = if got.len() == 1 {
            format!("index {i}")
        } else {
            format!("row {}, column {}", i / width, i % width)
        };
        return Err(input_error(
            py,
            format!("{name}: non-finite value ({v}) at {place}; NaN and infinity are refused"),
        ));
    }
    Ok(values)
}

/// A read-only view of an array whose dtype and rank were checked.
fn readonly<'py, T: Element, D: Dimension>(
    name: &str,
    array: &Bound<'py, PyUntypedArray>,
) -> PyResult<PyReadonlyArray<'py, T, D>> {
    let typed = array.cast::<PyArray<T, D>>()?;
    typed.try_readonly().map_err(|e| {
        input_error(
            array.py(),
            format!("{name}: the array cannot be read ({e})"),
        )
    })
}

/// The argument `name` as an image: a float array of shape (height, width, 3), every value
/// finite, copied once into an `RgbImage` (float64 is rounded to float32, as an EXR stores it).
pub fn image_from_array(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<RgbImage> {
    let py = obj.py();
    let values = floats::<numpy::Ix3>(name, obj, &[Size::Any("H"), Size::Any("W"), Size::Is(3)])?;
    let shape = values.shape();
    let (h, w) = (shape[0], shape[1]);
    if h == 0 || w == 0 || h > u32::MAX as usize || w > u32::MAX as usize {
        return Err(input_error(
            py,
            format!("{name}: an image needs at least one pixel, got shape ({h}, {w}, 3)"),
        ));
    }
    let pixels: Vec<[f32; 3]> = match &values {
        // A C-ordered array is one memcpy; any other layout is read pixel by pixel.
        Floats::F32(a) => match a.as_array().as_slice() {
            Some(flat) => bytemuck::cast_slice::<f32, [f32; 3]>(flat).to_vec(),
            None => a
                .as_array()
                .rows()
                .into_iter()
                .map(|p| [p[0], p[1], p[2]])
                .collect(),
        },
        Floats::F64(a) => a
            .as_array()
            .rows()
            .into_iter()
            .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
            .collect(),
    };
    let image = RgbImage {
        width: w as u32,
        height: h as u32,
        pixels,
    };
    let rounded = matches!(values, Floats::F64(_));
    if let Some((x, y, c)) = rounded
        .then(|| pgt::metrics::first_non_finite(&image))
        .flatten()
    {
        return Err(input_error(
            py,
            format!(
                "{name}: value {:?} at pixel ({x}, {y}), channel {} is beyond the range of float32",
                values.get((y as usize, x as usize, c)),
                pgt::metrics::CHANNELS[c]
            ),
        ));
    }
    Ok(image)
}
