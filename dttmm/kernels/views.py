"""A flat structure's tables as views of its buffers, made in compiled code (docs/flat_model.md,
"The accessors").

`table_view(field, buffer, shape, sizes)` is the accessor of table `field` of a flat structure
(kernels/schema.py: a FlatModel, a FlatLoops): a numba intrinsic that, called on it in a kernel,
gives the C-contiguous view of `buffer` ("real" or "int") at offset start[field] of the schema's
`shape` (per axis a constant, a size's name in `sizes`, or "name+constant": the sizes read from
the structure's `size`).

It is written as LLVM code, not as Python: a view written in Python (a slice, then a reshape)
and inlined where it is read cost each kernel ~55 ms of compile per read (typing and lowering
the reshape's checks; the general loop reads ~150), this ~10 ms (120 reads in one function,
numba's pass timings); tests/test_schema.py checks each accessor against numpy.  The view
borrows the buffer's memory (its meminfo: a reference where the caller counts them).
"""
from numba import config
from numba.core import cgutils, types
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array

from .schema import SIZES, axes, size_index, table_of

# a flat structure's fields in order (kernels/schema.py::FlatModel)
_POSITION = {"real": 0, "int": 1}
_START, _SIZE = 2, 3


def _load(builder, context, array, index):
    return builder.load(builder.gep(array.data, [context.get_constant(types.intp, index)]))


def table_view(field, buffer, shape, sizes=SIZES):
    """The accessor of table `field` (its index in the schema) of `buffer`, of the schema's
    `shape` in terms of `sizes`; with no axes, the table's one value."""
    if config.DISABLE_JIT:      # (numba off: the same view by numpy, its indexing checked)
        return lambda m: table_of(m, field, buffer, shape, sizes)
    position = _POSITION[buffer]
    index = size_index(sizes)
    dims = [(None if name is None else index[name], constant, plus)
            for name, constant, plus in axes(shape)]

    @intrinsic
    def accessor(typingctx, m):
        element = m.types[position].dtype
        result = types.Array(element, len(dims), "C") if dims else element

        def codegen(context, builder, signature, args):
            tuple_type, value = signature.args[0], args[0]

            def member(i):
                return make_array(tuple_type.types[i])(context, builder,
                                                       builder.extract_value(value, i))
            data, start, size = member(position), member(_START), member(_SIZE)
            offset = _load(builder, context, start, field)
            pointer = builder.gep(data.data, [offset])
            if not dims:
                return builder.load(pointer)
            extents = []
            for i, constant, plus in dims:
                extent = (context.get_constant(types.intp, constant) if i is None
                          else _load(builder, context, size, i))
                if i is not None and plus:
                    extent = builder.add(extent, context.get_constant(types.intp, plus))
                extents.append(extent)
            itemsize = context.get_constant(types.intp, context.get_abi_sizeof(
                context.get_data_type(element)))
            strides, stride = [None] * len(dims), itemsize
            for axis in range(len(dims) - 1, -1, -1):     # C order
                strides[axis] = stride
                stride = builder.mul(stride, extents[axis])
            view = make_array(result)(context, builder)
            populate_array(view, data=pointer, shape=cgutils.pack_array(builder, extents),
                           strides=cgutils.pack_array(builder, strides), itemsize=itemsize,
                           meminfo=data.meminfo, parent=data.parent)
            return impl_ret_borrowed(context, builder, result, view._getvalue())

        return result(m), codegen

    return accessor

